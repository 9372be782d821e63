#include "core/fresh_memory.h"

#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>

#include "core/parallel.h"

#ifndef MADV_POPULATE_WRITE
#define MADV_POPULATE_WRITE 23  // Linux 5.14
#endif

namespace candi {

void FaultInParallel(void* p, size_t bytes) {
  if (bytes == 0) return;
  const uintptr_t page = static_cast<uintptr_t>(sysconf(_SC_PAGESIZE));
  constexpr uintptr_t kBlock = uintptr_t{4} << 20;  // a task's share
  const uintptr_t begin = reinterpret_cast<uintptr_t>(p) / page * page;
  const uintptr_t end = (reinterpret_cast<uintptr_t>(p) + bytes + page - 1) / page * page;
  const size_t blocks = (end - begin + kBlock - 1) / kBlock;
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    const uintptr_t from = begin + b * kBlock, to = std::min(end, from + kBlock);
    if (madvise(reinterpret_cast<void*>(from), to - from, MADV_POPULATE_WRITE) == 0) return;
    // The pages at either end may hold bytes of other objects: an atomic or of 0 is a write
    // fault that changes nothing.
    for (uintptr_t q = from; q < to; q += page) {
      __atomic_fetch_or(reinterpret_cast<uint8_t*>(q), 0, __ATOMIC_RELAXED);
    }
  });
}

void AdviseHugePages(void* p, size_t bytes) {
  constexpr uintptr_t kHuge = uintptr_t{2} << 20;
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(p) + kHuge - 1) / kHuge * kHuge;
  const uintptr_t end = (reinterpret_cast<uintptr_t>(p) + bytes) / kHuge * kHuge;
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);  // advice only
}

void FreshBuffer::Reserve(size_t bytes) {
  if (bytes <= capacity_) return;
  std::unique_ptr<uint8_t[]> grown(new uint8_t[bytes]);
  FaultInParallel(grown.get(), bytes);
  if (size_ > 0) std::memcpy(grown.get(), data_.get(), size_);
  data_ = std::move(grown);
  capacity_ = bytes;
}

void FreshBuffer::Append(const uint8_t* p, size_t bytes) {
  if (bytes > 0) std::memcpy(Extend(bytes), p, bytes);
}

uint8_t* FreshBuffer::Extend(size_t bytes) {
  if (size_ + bytes > capacity_) {
    Reserve(std::max({size_ + bytes, 2 * capacity_, size_t{1} << 26}));
  }
  uint8_t* at = data_.get() + size_;
  size_ += bytes;
  return at;
}

void FreshBuffer::Release() {
  data_.reset();
  size_ = capacity_ = 0;
}

}  // namespace candi

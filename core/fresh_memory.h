// Large buffers of fresh memory, their pages faulted in by several threads.
//
// The first touch of a page costs the kernel a zeroing and, on a virtual machine, a fault in
// the host: one thread writing a buffer of gigabytes spends most of its time there (4 GiB: 1.8-
// 3.2 s on one thread, 0.7-0.9 s on two, on the project's 2-core VM).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>

namespace candi {

// Faults in the pages of [p, p + bytes) on the pool's threads (MADV_POPULATE_WRITE, or a write
// to each page on kernels before 5.14). The contents are undefined afterwards: for memory not
// yet written.
void FaultInParallel(void* p, size_t bytes);

// Asks the kernel to back the whole 2 MiB pages inside [p, p + bytes) with transparent huge
// pages when they are first touched (MADV_HUGEPAGE; nothing where THP is off). For buffers of
// tens of MB written all over, cell after cell, such as a sort's buckets: thousands of places
// written in step miss the TLB on 4 KiB pages. Not for gigabytes touched once, whose huge
// pages cost more to fault in on the project's VM than small ones.
void AdviseHugePages(void* p, size_t bytes);

// Grows v's capacity to at least n (with a quarter more, so that sizes that vary little reuse
// it), into memory advised for huge pages; v's elements are dropped when it grows.
template <typename Vector>
void ReserveHuge(Vector* v, size_t n) {
  if (v->capacity() >= n) return;
  v->clear();
  v->shrink_to_fit();
  v->reserve(n + n / 4);
  AdviseHugePages(v->data(), v->capacity() * sizeof(*v->data()));
}

// A byte buffer that grows (by doubling) into fresh memory faulted in by several threads, its
// contents copied over; not zero-filled.
class FreshBuffer {
 public:
  // Capacity for at least `bytes` in all.
  void Reserve(size_t bytes);
  void Append(const uint8_t* p, size_t bytes);
  // Grows the size by `bytes`; returns where they start (their contents undefined).
  uint8_t* Extend(size_t bytes);
  // Frees the memory.
  void Release();
  const uint8_t* data() const { return data_.get(); }
  size_t size() const { return size_; }

 private:
  std::unique_ptr<uint8_t[]> data_;
  size_t size_ = 0, capacity_ = 0;
};

}  // namespace candi

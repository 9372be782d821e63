#include "io/byte_stream.h"

#include <algorithm>
#include <cstring>
#include <vector>

#include "core/parallel.h"

namespace candi::io {

namespace {
constexpr size_t kParallelPart = size_t{4} << 20;  // bytes a thread copies at least
}  // namespace

size_t ReadAtInParts(const BinaryFile& file, uint64_t offset, void* dst, size_t n) {
  if (n < 2 * kParallelPart) return file.ReadAt(offset, dst, n);
  // The copy out of the page cache is the cost of a read of a cached file; in one part it would
  // run on one core while the others wait.
  auto* out = static_cast<uint8_t*>(dst);
  const size_t parts = std::min<size_t>(16, n / kParallelPart);
  std::vector<size_t> got(parts, 0);
  auto begin = [&](size_t k) { return n * k / parts; };
  ParallelFor(size_t{0}, parts, [&](size_t k) {
    got[k] = file.ReadAt(offset + begin(k), out + begin(k), begin(k + 1) - begin(k));
  });
  size_t total = 0;  // the bytes read without a gap (a part falls short only at the end)
  for (size_t k = 0; k < parts; ++k) {
    total += got[k];
    if (got[k] < begin(k + 1) - begin(k)) break;
  }
  return total;
}

ByteStream::ByteStream(BinaryFile& file, size_t block_size)
    : file_(&file), block_size_(block_size), offset_(file.position()) {}

ByteStream::ByteStream(const MappedFile& map, uint64_t offset) : map_(&map), offset_(offset) {}

bool ByteStream::Ensure(size_t n) {
  if (map_) return available() >= n;
  if (end_ - begin_ >= n) return true;
  // Move what is left to the front, grow if needed, then fill.
  const size_t left = end_ - begin_;
  if (begin_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + begin_, left);
    begin_ = 0;
    end_ = left;
  }
  // No larger than the rest of the file: a small file does not get a block-sized buffer.
  const size_t want = std::max<size_t>(n, std::min<uint64_t>(block_size_, left + file_->remaining()));
  if (buffer_.size() < want) buffer_.resize(want);
  while (end_ < n) {
    const size_t want = static_cast<size_t>(std::min<uint64_t>(buffer_.size() - end_, file_->remaining()));
    const uint64_t at = file_->position();
    const size_t got = ReadAtInParts(*file_, at, buffer_.data() + end_, want);
    file_->Seek(at + got);
    if (got == 0) return false;
    end_ += got;
  }
  return true;
}

}  // namespace candi::io

#include "core/byte_stream.h"

#include <algorithm>
#include <cstring>

namespace candi {

ByteStream::ByteStream(BinaryFile& file, size_t block_size)
    : file_(file), block_size_(block_size), offset_(file.position()) {}

bool ByteStream::Ensure(size_t n) {
  if (end_ - begin_ >= n) return true;
  // Move what is left to the front, grow if needed, then fill.
  const size_t left = end_ - begin_;
  if (begin_ > 0) {
    std::memmove(buffer_.data(), buffer_.data() + begin_, left);
    begin_ = 0;
    end_ = left;
  }
  // No larger than the rest of the file: a small file does not get a block-sized buffer.
  const size_t want = std::max<size_t>(n, std::min<uint64_t>(block_size_, left + file_.remaining()));
  if (buffer_.size() < want) buffer_.resize(want);
  while (end_ < n) {
    const size_t got = file_.ReadSome(buffer_.data() + end_, buffer_.size() - end_);
    if (got == 0) return false;
    end_ += got;
  }
  return true;
}

}  // namespace candi

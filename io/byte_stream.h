// ByteStream: a growable read-ahead window over a BinaryFile, for parsers that need "the next n
// bytes" without knowing record sizes in advance (PLY list properties, text lines). Over a
// MappedFile the window is the rest of the map: nothing is copied, and Ensure(n) is true exactly
// when it would be over the file.
#pragma once

#include <cstdint>
#include <vector>

#include "core/binary_file.h"
#include "core/mapped_file.h"

namespace candi::io {

// Reads like file.ReadAt (up to n bytes at offset; fewer only at the end of the file), copying
// reads of 8 MiB and more out of the page cache in parallel parts. Returns the bytes read.
size_t ReadAtInParts(const BinaryFile& file, uint64_t offset, void* dst, size_t n);

class ByteStream {
 public:
  // Starts at the file's current position.
  explicit ByteStream(BinaryFile& file, size_t block_size = 8 << 20);
  // Over the map from byte `offset` (<= map.size()); the map must outlive the stream.
  ByteStream(const MappedFile& map, uint64_t offset);

  // Makes at least n bytes available at data(); false when the file ends first (available()
  // then holds what is left).
  bool Ensure(size_t n);
  const uint8_t* data() const { return map_ ? map_->data() + offset_ : buffer_.data() + begin_; }
  size_t available() const {
    return map_ ? static_cast<size_t>(map_->size() - offset_) : end_ - begin_;
  }
  void Consume(size_t n) {
    begin_ += n;
    offset_ += n;
  }
  uint64_t offset() const { return offset_; }  // file offset of data()
  bool AtEnd() { return !Ensure(1); }

 private:
  BinaryFile* file_ = nullptr;      // the file read, or
  const MappedFile* map_ = nullptr;  // the map read from
  size_t block_size_ = 0;
  std::vector<uint8_t> buffer_;
  size_t begin_ = 0, end_ = 0;
  uint64_t offset_ = 0;
};

}  // namespace candi::io

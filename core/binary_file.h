// Sequential reading of a file with 64-bit positions, for the point-format parsers.
//
// Reads go straight into the caller's buffer (pread), so a parser decodes from its own chunk
// buffer with no extra copy. Every failure throws InputError naming the path and byte position.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>

namespace candi {

// Opens `path` read-only (close-on-exec) and returns the descriptor, with the file's size in *size
// and, when `regular` is given, whether it is a regular file. Throws InputError naming the path
// when it cannot be opened or stat'ed, or is a directory.
int OpenForReading(const std::string& path, uint64_t* size, bool* regular = nullptr);

class BinaryFile {
 public:
  explicit BinaryFile(const std::string& path);
  ~BinaryFile();
  BinaryFile(const BinaryFile&) = delete;
  BinaryFile& operator=(const BinaryFile&) = delete;

  const std::string& path() const { return path_; }
  uint64_t size() const { return size_; }
  uint64_t position() const { return position_; }
  uint64_t remaining() const { return size_ - position_; }
  void Seek(uint64_t offset);

  // Reads exactly n bytes; on a short file throws "<path>: byte <pos>: unexpected end of file
  // while reading <what> (needed n bytes, k left)".
  void ReadExact(void* dst, size_t n, const std::string& what);
  // Reads up to n bytes; returns the number read (0 at the end).
  size_t ReadSome(void* dst, size_t n);
  // Reads up to n bytes at `offset` without moving; returns the number read (fewer only at the
  // end). Safe to call from several threads at once.
  size_t ReadAt(uint64_t offset, void* dst, size_t n) const;
  // Reads a text line (without "\n" or "\r\n") of at most max_length bytes; false at the end.
  bool ReadLine(std::string* line, size_t max_length = 1 << 16);
  // Bytes at the start of the file (fewer if the file is shorter), without moving.
  std::string Peek(size_t n) const;

 private:
  std::string path_;
  int fd_ = -1;
  uint64_t size_ = 0, position_ = 0;
};

// Byte order helpers.
template <typename T>
inline T LoadLE(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;  // candi targets little-endian hosts (x86-64, aarch64); CMake checks it
}
template <typename T>
inline void StoreLE(uint8_t* p, T v) {
  std::memcpy(p, &v, sizeof(T));
}
template <typename T>
inline T ByteSwap(T v) {
  uint8_t b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  std::memcpy(&v, b, sizeof(T));
  return v;
}

}  // namespace candi

// SHA-256 (FIPS 180-4) of bytes or of a file, as lowercase hex: the provenance hashes of
// archive.json (which exact source file a layer came from). Thread-safe (no shared state).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace candi {

class Sha256 {
 public:
  Sha256();
  void Update(const void* data, size_t size);
  std::string HexDigest();  // finishes; the object must not be updated afterwards

 private:
  void Block(const uint8_t* block);
  uint32_t h_[8];
  uint8_t buffer_[64];
  size_t buffered_ = 0;
  uint64_t length_ = 0;
};

std::string Sha256Hex(const std::string& bytes);
// Streams the file (1 MiB reads); throws InputError naming the path when it cannot be read.
std::string Sha256OfFile(const std::string& path);

}  // namespace candi

// SHA-256 (FIPS 180-4) of bytes or of a file, as lowercase hex: the provenance hashes of
// archive.json (which exact source file a layer came from). Thread-safe (no shared state).
// libcrypto computes it (see sha256.cc).
#pragma once

#include <cstddef>
#include <memory>
#include <string>

namespace candi {

class Sha256 {
 public:
  Sha256();
  ~Sha256();
  Sha256(Sha256&&) noexcept;
  Sha256& operator=(Sha256&&) noexcept;
  void Update(const void* data, size_t size);
  std::string HexDigest();  // finishes; the object must not be updated afterwards

 private:
  struct Impl;  // libcrypto's digest context, kept out of this header
  std::unique_ptr<Impl> impl_;
};

std::string Sha256Hex(const std::string& bytes);
// Streams the file (1 MiB reads); throws InputError naming the path when it cannot be read.
std::string Sha256OfFile(const std::string& path);

}  // namespace candi

#include "core/sha256.h"

#include <openssl/evp.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <vector>

#include "core/check.h"

namespace candi {

// libcrypto rather than portable C: it picks the CPU's SHA extensions (or AVX2/SSSE3 where they
// are missing) at run time and hashes about 7 times faster, 2 times without SHA extensions
// (bench/sha256_bench.cc; nettle 3.8 was slower than libcrypto on both).
struct Sha256::Impl {
  EVP_MD_CTX* context = EVP_MD_CTX_new();
  ~Impl() { EVP_MD_CTX_free(context); }
};

namespace {
// libcrypto fails only when out of memory or misconfigured (a provider without SHA-256).
void Require(bool ok, const char* call) {
  if (!ok) throw std::runtime_error(std::string("SHA-256: libcrypto's ") + call + " failed");
}
}  // namespace

Sha256::Sha256() : impl_(std::make_unique<Impl>()) {
  Require(impl_->context != nullptr, "EVP_MD_CTX_new");
  Require(EVP_DigestInit_ex(impl_->context, EVP_sha256(), nullptr) == 1, "EVP_DigestInit_ex");
}
Sha256::~Sha256() = default;
Sha256::Sha256(Sha256&&) noexcept = default;
Sha256& Sha256::operator=(Sha256&&) noexcept = default;

void Sha256::Update(const void* data, size_t size) {
  Require(EVP_DigestUpdate(impl_->context, data, size) == 1, "EVP_DigestUpdate");
}

std::string Sha256::HexDigest() {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int size = 0;
  Require(EVP_DigestFinal_ex(impl_->context, digest, &size) == 1, "EVP_DigestFinal_ex");
  static const char* kHex = "0123456789abcdef";
  std::string hex;
  for (unsigned int i = 0; i < size; ++i) hex += kHex[digest[i] >> 4], hex += kHex[digest[i] & 15];
  return hex;
}

std::string Sha256Hex(const std::string& bytes) {
  Sha256 sha;
  sha.Update(bytes.data(), bytes.size());
  return sha.HexDigest();
}

std::string Sha256OfFile(const std::string& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), std::fclose);
  if (!f) throw InputError(path, "", std::string("cannot open: ") + std::strerror(errno));
  Sha256 sha;
  std::vector<char> buffer(1 << 20);
  size_t n;
  while ((n = std::fread(buffer.data(), 1, buffer.size(), f.get())) > 0) sha.Update(buffer.data(), n);
  if (std::ferror(f.get())) throw InputError(path, "", std::string("read error: ") + std::strerror(errno));
  return sha.HexDigest();
}

}  // namespace candi

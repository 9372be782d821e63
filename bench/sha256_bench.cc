// SHA-256 throughput: candi's core/sha256 (the provenance hashes of `candi build`; libcrypto since
// it replaced portable C, which this program measured at commit 366d459 together with nettle)
// against libcrypto's EVP called directly, which it should match, over one buffer of 1 GiB of
// pseudo-random bytes fed in 1 MiB pieces (as Sha256OfFile reads a file), and Sha256OfFile over
// the same bytes written to $TMPDIR (page cache, so the read is a memcpy).
// The implementations take turns run by run, so a burst of load on a shared machine hits them
// alike; prints the median, min and max MB/s (10^6 bytes/s) of wall time and of this thread's CPU
// time. One thread; pin it with `taskset -c 0`. All digests must agree (exit 1 otherwise).
//
// Usage: sha256_bench [core|openssl|file]...   (default: all three)
// Environment: CANDI_BENCH_SHA256_MB (buffer size in MiB, default 1024), CANDI_BENCH_RUNS
// (default 5). Under valgrind (callgrind) use e.g. CANDI_BENCH_SHA256_MB=64 CANDI_BENCH_RUNS=1
// and one implementation; valgrind's CPU lacks the SHA extensions, so libcrypto takes its AVX2
// path there (as it does natively with OPENSSL_ia32cap=":~0x20000000").
#include <openssl/evp.h>

#include <time.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/rng.h"
#include "core/sha256.h"

namespace {

using candi::Sha256;

constexpr size_t kPiece = size_t{1} << 20;

size_t EnvOr(const char* name, size_t fallback) {
  const char* v = std::getenv(name);
  return v ? std::strtoull(v, nullptr, 10) : fallback;
}

std::string Hex(const unsigned char* digest, size_t size) {
  static const char* kDigits = "0123456789abcdef";
  std::string hex;
  for (size_t i = 0; i < size; ++i) hex += kDigits[digest[i] >> 4], hex += kDigits[digest[i] & 15];
  return hex;
}

std::string HashCore(const std::vector<uint8_t>& bytes) {
  Sha256 sha;
  for (size_t at = 0; at < bytes.size(); at += kPiece)
    sha.Update(bytes.data() + at, std::min(kPiece, bytes.size() - at));
  return sha.HexDigest();
}

std::string HashOpenSsl(const std::vector<uint8_t>& bytes) {
  EVP_MD_CTX* ctx = EVP_MD_CTX_new();
  EVP_DigestInit_ex(ctx, EVP_sha256(), nullptr);
  for (size_t at = 0; at < bytes.size(); at += kPiece)
    EVP_DigestUpdate(ctx, bytes.data() + at, std::min(kPiece, bytes.size() - at));
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int size = 0;
  EVP_DigestFinal_ex(ctx, digest, &size);
  EVP_MD_CTX_free(ctx);
  return Hex(digest, size);
}

double Seconds(clockid_t clock) {
  timespec t;
  clock_gettime(clock, &t);
  return t.tv_sec + 1e-9 * t.tv_nsec;
}

struct Times {
  std::vector<double> wall_mbs, cpu_mbs;
};

void PrintRow(const std::string& name, Times t, size_t runs) {
  auto stats = [](std::vector<double>& v) {
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    const double median = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
    char text[64];
    std::snprintf(text, sizeof(text), "%8.0f %7.0f %7.0f", median, v.front(), v.back());
    return std::string(text);
  };
  std::printf("%-8s %5zu  %s   %s\n", name.c_str(), runs, stats(t.wall_mbs).c_str(),
              stats(t.cpu_mbs).c_str());
}

}  // namespace

int main(int argc, char** argv) {
  const size_t bytes_count = EnvOr("CANDI_BENCH_SHA256_MB", 1024) << 20;
  const size_t runs = std::max<size_t>(1, EnvOr("CANDI_BENCH_RUNS", 5));
  std::vector<std::string> chosen(argv + 1, argv + argc);
  if (chosen.empty()) chosen = {"core", "openssl", "file"};

  std::vector<uint8_t> bytes(bytes_count);
  candi::Rng rng(1);
  for (size_t i = 0; i + 8 <= bytes.size(); i += 8) {
    const uint64_t v = rng.Next();
    std::memcpy(&bytes[i], &v, 8);
  }
  const char* tmp = std::getenv("TMPDIR");
  const std::string file = std::string(tmp ? tmp : "/tmp") + "/candi-sha256-bench.bin";
  if (std::find(chosen.begin(), chosen.end(), "file") != chosen.end()) {
    std::ofstream(file, std::ios::binary)
        .write(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }

  const std::map<std::string, std::function<std::string()>> hashers = {
      {"core", [&] { return HashCore(bytes); }},
      {"openssl", [&] { return HashOpenSsl(bytes); }},
      {"file", [&] { return candi::Sha256OfFile(file); }}};
  std::map<std::string, Times> times;
  std::string reference;
  for (size_t r = 0; r < runs; ++r) {
    for (const std::string& name : chosen) {
      const auto it = hashers.find(name);
      if (it == hashers.end())
        return std::fprintf(stderr, "unknown implementation '%s'\n", name.c_str()), 2;
      const double wall = Seconds(CLOCK_MONOTONIC), cpu = Seconds(CLOCK_THREAD_CPUTIME_ID);
      const std::string digest = it->second();
      const double mb = bytes.size() / 1e6;
      times[name].wall_mbs.push_back(mb / (Seconds(CLOCK_MONOTONIC) - wall));
      times[name].cpu_mbs.push_back(mb / (Seconds(CLOCK_THREAD_CPUTIME_ID) - cpu));
      if (reference.empty()) reference = digest;
      if (digest != reference) {
        std::fprintf(stderr, "%s: digest %s differs from %s\n", name.c_str(), digest.c_str(),
                     reference.c_str());
        return 1;
      }
    }
  }
  std::filesystem::remove(file);
  std::printf("SHA-256 of %zu MiB, 1 MiB pieces, one thread; MB/s = 10^6 bytes/s; digest %s\n",
              bytes.size() >> 20, reference.c_str());
  std::printf("%-8s %5s  %8s %7s %7s   %8s %7s %7s\n", "impl", "runs", "wall med", "min", "max",
              "cpu med", "min", "max");
  for (const std::string& name : chosen) PrintRow(name, times[name], runs);
  return 0;
}

// Seeded, platform-independent random numbers.
//
// std::uniform_*_distribution differ between standard libraries, so candi draws its own numbers
// from a counter-based hash (SplitMix64 finaliser): the same seed gives the same numbers on every
// platform and, since HashIndex needs no state, whatever the thread count or chunking.
#pragma once

#include <cstdint>

namespace candi {

// x rotated left by k bits, 0 < k < 64 (compiles to one rotate instruction).
inline uint64_t Rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }

// SplitMix64 finaliser: a bijective 64-bit mix with full avalanche.
inline uint64_t Mix64(uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// The part of HashIndex that depends on the seed and stream only, for loops to hoist:
// HashIndex(seed, index, stream) == Mix64(HashStreamKey(seed, stream) ^ index).
inline uint64_t HashStreamKey(uint64_t seed, uint64_t stream = 0) { return Mix64(seed ^ Mix64(stream)); }

// A stateless random value for item `index` in stream `stream` under `seed`.
inline uint64_t HashIndex(uint64_t seed, uint64_t index, uint64_t stream = 0) {
  return Mix64(HashStreamKey(seed, stream) ^ index);
}

// Uniform double in [0, 1) from the top 53 bits.
inline double ToUnit(uint64_t bits) { return static_cast<double>(bits >> 11) * 0x1.0p-53; }

// A sequential generator (xoshiro256**), seeded through SplitMix64. Not thread-safe: give each
// task its own, seeded from HashIndex(seed, task). Construction and Next are inline: shuffles and
// samplers call them in their inner loops.
class Rng {
 public:
  explicit Rng(uint64_t seed) {
    uint64_t z = seed;
    for (auto& s : s_) {
      z += 0x9e3779b97f4a7c15ULL;
      s = Mix64(z);
    }
  }
  uint64_t Next() {
    const uint64_t result = Rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = Rotl(s_[3], 45);
    return result;
  }
  double Uniform() { return ToUnit(Next()); }             // [0, 1)
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  uint64_t Below(uint64_t n);                              // [0, n), unbiased; n > 0
  double Normal();                                         // standard normal (Box-Muller)

 private:
  uint64_t s_[4];
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace candi

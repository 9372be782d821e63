// Frame buffers of the SPBR renderer: packed 64-bit z-buffer keys and exact integer accumulation
// (RGB sums and hit counts).
//
// Key: the depth's order-preserving 32-bit image in the high word, the colour (0x00RRGGBB) in the
// low word. The minimum key is the nearest point; equal depths resolve by colour, so the result
// does not depend on the order points arrive in.
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

#include "core/point_cloud.h"

namespace candi::render {

constexpr uint64_t kEmptyKey = ~uint64_t{0};

// Order-preserving map of a float to uint32 (negative depths sort before positive ones).
inline uint32_t DepthBits(float depth) {
  uint32_t bits;
  std::memcpy(&bits, &depth, sizeof(bits));
  return bits ^ ((bits >> 31) ? 0xffffffffu : 0x80000000u);
}

inline uint64_t PackKey(float depth, Rgb8 c) {
  return (static_cast<uint64_t>(DepthBits(depth)) << 32) |
         (static_cast<uint32_t>(c.r) << 16 | static_cast<uint32_t>(c.g) << 8 | c.b);
}

// Exact sums over ensembles: per pixel R, G, B sums and the number of ensembles with a point.
// uint32 holds 16.8 M ensembles of full white: far beyond any repeat level.
// Pixels of one ensemble per grey level (the brightness gain's percentile is read from it).
using GreyHistogram = std::array<uint64_t, 256>;

// The grey level (Rec. 601 luma, rounded) of a key's colour.
inline int KeyGrey(uint64_t key) {
  const int r = (key >> 16) & 0xff, g = (key >> 8) & 0xff, b = key & 0xff;
  return (299 * r + 587 * g + 114 * b + 500) / 1000;
}

struct Accumulator {
  int width = 0, height = 0;
  std::vector<uint32_t> sums;  // 4 per pixel: R, G, B, hits
  Accumulator() = default;
  Accumulator(int w, int h) : width(w), height(h), sums(4 * static_cast<size_t>(w) * h, 0) {}
  void Add(size_t pixel, uint64_t key) {
    uint32_t* s = &sums[4 * pixel];
    s[0] += static_cast<uint32_t>(key >> 16) & 0xff;
    s[1] += static_cast<uint32_t>(key >> 8) & 0xff;
    s[2] += static_cast<uint32_t>(key) & 0xff;
    s[3] += 1;
  }
  void Merge(const Accumulator& other);
  bool operator==(const Accumulator& o) const { return sums == o.sums; }
};

}  // namespace candi::render

// Morton (Z-order) codes: three 21-bit cell coordinates interleaved into 63 bits, x in the lowest
// bit of each triple. Points sorted by their codes are near each other in space, which the render
// archive's chunks and the deviation queries' order rely on.
#pragma once

#include <cstdint>

namespace candi {

// The low 21 bits of v spread to every third bit (bit k to bit 3k).
inline uint64_t MortonSpread21(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

// The code of cell (x, y, z), each coordinate's low 21 bits.
inline uint64_t MortonCode21(uint64_t x, uint64_t y, uint64_t z) {
  return MortonSpread21(x) | MortonSpread21(y) << 1 | MortonSpread21(z) << 2;
}

}  // namespace candi

#include "render/pack_records.h"

#include <algorithm>
#include <type_traits>

#include "core/simd.h"

namespace candi::render::pack_internal {

namespace {

constexpr size_t kBlock = 256;  // points a block: the kernels' arrays stay in L1

// A block's coordinates, one array per axis.
template <typename P>
struct Coordinates {
  decltype(P::x) c[3][kBlock];
  __attribute__((always_inline)) inline Coordinates(const P* __restrict p, size_t m) {
    for (size_t i = 0; i < m; ++i) {
      c[0][i] = p[i].x;
      c[1][i] = p[i].y;
      c[2][i] = p[i].z;
    }
  }
};

// Calls body(xyz, base, m) for each block points[base, base + m) of points[0, n), xyz its coordinates.
template <typename P, typename Body>
__attribute__((always_inline)) inline void ForBlocks(const P* points, size_t n, Body&& body) {
  for (size_t base = 0; base < n; base += kBlock) {
    const size_t m = std::min(kBlock, n - base);
    const Coordinates<P> xyz(points + base, m);
    body(xyz, base, m);
  }
}

// Calls body(position) with Position(f)'s operations on axis a as a function of the record's
// coordinate, so the body's loop over a block inlines and vectorizes them.
template <typename P, typename Body>
__attribute__((always_inline)) inline void WithPosition(const RecordFrame& f, int a, Body&& body) {
  const double s = f.shift[a];
  if constexpr (std::is_same_v<P, CompactPoint>) {
    body([s](float x) { return double{x} + s; });
  } else if constexpr (std::is_same_v<P, LasPoint>) {
    if (f.las.decimal) {
      const double o = f.las.integer_offset[a], d = f.las.divisor[a];
      body([s, o, d](int32_t x) { return (x + o) / d + s; });
    } else {
      const double k = f.las.scale[a], o = f.las.offset[a];
      body([s, k, o](int32_t x) { return (x * k + o) + s; });
    }
  } else {
    body([](double x) { return x; });
  }
}

// MortonGrid::Quantize's operations on one coordinate: its cell, 21 bits.
template <typename Position, typename T>
__attribute__((always_inline)) inline uint32_t GridCell(const Position& position, T c, double lo, double scale) {
  const double top = static_cast<double>((1 << kMortonBits) - 1);
  double t = (position(c) - lo) * scale;
  t = t < 0.0 ? 0.0 : t;  // std::clamp(t, 0.0, top)
  t = top < t ? top : t;
  return static_cast<uint32_t>(static_cast<int32_t>(t));
}

// ChunkQuantizer::Encode of a block, one axis at a time: its operations on each coordinate in the
// same order (so the same words). Coordinates are finite here, so the clamp's two comparisons are
// std::clamp's, and a clamped value below 2^24 converts through int32 exactly.
template <typename P>
__attribute__((always_inline)) inline void EncodeRun(const ChunkQuantizer& q, const RecordFrame& f, const P* points,
                                                     size_t n, uint64_t* words) {
  ForBlocks(points, n, [&](const Coordinates<P>& xyz, size_t base, size_t m) {
    uint64_t* __restrict w = words + base;
    for (size_t i = 0; i < m; ++i) w[i] = points[base + i].rgb & 0xffffff;
    int shift = 24;
    for (int a = 0; a < 3; ++a) {
      if (q.bits[a] == 0) continue;
      const double lo = q.box.min[a], step = q.step[a];
      const double top = static_cast<double>((uint64_t{1} << q.bits[a]) - 1);
      const auto* __restrict c = xyz.c[a];
      WithPosition<P>(f, a, [&](auto position) {
        for (size_t i = 0; i < m; ++i) {
          double t = std::nearbyint((position(c[i]) - lo) / step);
          t = t < 0.0 ? 0.0 : t;
          t = top < t ? top : t;
          w[i] |= static_cast<uint64_t>(static_cast<int32_t>(t)) << shift;
        }
      });
      shift += q.bits[a];
    }
  });
}

// MortonGrid::Code of points[0, n), a block and an axis at a time.
template <typename P>
__attribute__((always_inline)) inline void CodesRun(const MortonGrid& g, const RecordFrame& f, const P* points,
                                                    size_t n, uint64_t* codes) {
  ForBlocks(points, n, [&](const Coordinates<P>& xyz, size_t base, size_t m) {
    uint64_t* __restrict out = codes + base;
    for (size_t i = 0; i < m; ++i) out[i] = 0;
    for (int a = 0; a < 3; ++a) {
      const double lo = g.min[a], scale = g.scale[a];
      const auto* __restrict c = xyz.c[a];
      WithPosition<P>(f, a, [&](auto position) {
        for (size_t i = 0; i < m; ++i) out[i] |= MortonSpread21(GridCell(position, c[i], lo, scale)) << a;
      });
    }
  });
}

// (MortonGrid::Code >> 3 * shift) & (2^(3 * levels) - 1) of points[0, n), levels <= 3: only the
// cells' bits that make it, on 32 bits.
template <typename P>
__attribute__((always_inline)) inline void CellsRun(const MortonGrid& g, const RecordFrame& f, const P* points,
                                                    size_t n, int shift, int levels, uint16_t* cells) {
  const uint32_t mask = (uint32_t{1} << levels) - 1;
  uint32_t out[kBlock];
  ForBlocks(points, n, [&](const Coordinates<P>& xyz, size_t base, size_t m) {
    for (size_t i = 0; i < m; ++i) out[i] = 0;
    for (int a = 0; a < 3; ++a) {
      const double lo = g.min[a], scale = g.scale[a];
      const auto* __restrict c = xyz.c[a];
      WithPosition<P>(f, a, [&](auto position) {
        for (size_t i = 0; i < m; ++i) {
          const uint32_t b = (GridCell(position, c[i], lo, scale) >> shift) & mask;
          out[i] |= ((b & 1) | (b & 2) << 2 | (b & 4) << 4) << a;
        }
      });
    }
    for (size_t i = 0; i < m; ++i) cells[base + i] = static_cast<uint16_t>(out[i]);
  });
}

}  // namespace

#define CANDI_PACK_RECORD_KERNELS(P)                                                                     \
  CANDI_TARGET_CLONES_AVX512                                                                             \
  void MortonCodes(const MortonGrid& g, const RecordFrame& f, const P* points, size_t n, uint64_t* codes) { \
    CodesRun(g, f, points, n, codes);                                                                    \
  }                                                                                                      \
  CANDI_TARGET_CLONES_AVX512                                                                             \
  void MortonCells(const MortonGrid& g, const RecordFrame& f, const P* points, size_t n, int shift, int levels, \
                   uint16_t* cells) {                                                                    \
    CellsRun(g, f, points, n, shift, levels, cells);                                                     \
  }                                                                                                      \
  CANDI_TARGET_CLONES_AVX512                                                                             \
  void Encode(const ChunkQuantizer& q, const RecordFrame& f, const P* points, size_t n, uint64_t* words) { \
    EncodeRun(q, f, points, n, words);                                                                   \
  }

CANDI_PACK_RECORD_KERNELS(WidePoint)
CANDI_PACK_RECORD_KERNELS(CompactPoint)
CANDI_PACK_RECORD_KERNELS(LasPoint)

Box3d ChunkBox(const LasPoint* points, size_t n, const RecordFrame& f) {
  int32_t lo[3] = {points[0].x, points[0].y, points[0].z}, hi[3] = {lo[0], lo[1], lo[2]};
  for (size_t i = 1; i < n; ++i) {
    const int32_t c[3] = {points[i].x, points[i].y, points[i].z};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], c[a]);
      hi[a] = std::max(hi[a], c[a]);
    }
  }
  Box3d box;
  box.Extend(LasPoint{lo[0], lo[1], lo[2], 0}.Position(f));
  box.Extend(LasPoint{hi[0], hi[1], hi[2], 0}.Position(f));
  return box;
}

}  // namespace candi::render::pack_internal

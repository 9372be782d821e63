#include "render/pack_records.h"

#include <algorithm>
#include <type_traits>

#include "core/simd.h"

namespace candi::render::pack_internal {

namespace {

// One axis of LAS positions, Position's operations in a loop the compiler vectorizes.
__attribute__((always_inline)) inline void DecodeAxis(const LasPoint* __restrict p, size_t m, const RecordFrame& f,
                                                      int a, double* __restrict out) {
  int32_t c[256];
  for (size_t i = 0; i < m; ++i) c[i] = a == 0 ? p[i].x : a == 1 ? p[i].y : p[i].z;
  const double s = f.shift[a];
  if (f.las.decimal) {
    const double o = f.las.integer_offset[a], d = f.las.divisor[a];
    for (size_t i = 0; i < m; ++i) out[i] = (c[i] + o) / d + s;
  } else {
    const double k = f.las.scale[a], o = f.las.offset[a];
    for (size_t i = 0; i < m; ++i) out[i] = (c[i] * k + o) + s;
  }
}

template <typename P>
__attribute__((always_inline)) inline void EncodeRun(const ChunkQuantizer& q, const RecordFrame& f, const P* points,
                                                     size_t n, uint64_t* words) {
  if constexpr (std::is_same_v<P, LasPoint>) {
    // The divisions of a block's positions first, vectorized, then the encoding.
    double x[256], y[256], z[256];
    for (size_t base = 0; base < n; base += 256) {
      const size_t m = std::min<size_t>(256, n - base);
      DecodeAxis(points + base, m, f, 0, x);
      DecodeAxis(points + base, m, f, 1, y);
      DecodeAxis(points + base, m, f, 2, z);
      for (size_t i = 0; i < m; ++i) words[base + i] = q.Encode(Eigen::Vector3d(x[i], y[i], z[i]), points[base + i].rgb);
    }
  } else {
    for (size_t i = 0; i < n; ++i) words[i] = q.Encode(points[i].Position(f), points[i].rgb);
  }
}

// MortonSpread21(quantized coordinate) of c[0, m) on one axis, position(c) as Position gives it, then
// Quantize's operations on doubles.
template <typename T, typename Position>
__attribute__((always_inline)) inline void SpreadAxis(const T* __restrict c, size_t m, Position position, double lo,
                                                      double scale, uint64_t* __restrict out) {
  const double top = static_cast<double>((1 << kMortonBits) - 1);
  for (size_t i = 0; i < m; ++i) {
    double v = (position(c[i]) - lo) * scale;
    v = v < 0.0 ? 0.0 : v;  // std::clamp(v, 0.0, top)
    v = top < v ? top : v;
    out[i] = MortonSpread21(static_cast<uint64_t>(static_cast<int32_t>(v)));
  }
}

// One axis of Position(f) for each record type.
template <typename P>
__attribute__((always_inline)) inline void SpreadAxisOf(const decltype(P::x)* c, size_t m, const RecordFrame& f,
                                                        int a, const MortonGrid& g, uint64_t* out) {
  if constexpr (std::is_same_v<P, CompactPoint>) {
    const double s = f.shift[a];
    SpreadAxis(c, m, [s](float x) { return double{x} + s; }, g.min[a], g.scale[a], out);
  } else if constexpr (std::is_same_v<P, LasPoint>) {
    const double s = f.shift[a];
    if (f.las.decimal) {
      const double o = f.las.integer_offset[a], d = f.las.divisor[a];
      SpreadAxis(c, m, [s, o, d](int32_t x) { return (x + o) / d + s; }, g.min[a], g.scale[a], out);
    } else {
      const double k = f.las.scale[a], o = f.las.offset[a];
      SpreadAxis(c, m, [s, k, o](int32_t x) { return (x * k + o) + s; }, g.min[a], g.scale[a], out);
    }
  } else {
    SpreadAxis(c, m, [](double x) { return x; }, g.min[a], g.scale[a], out);
  }
}

// MortonGrid::Code of points[0, n), in blocks: the coordinates are copied out per axis, then each
// axis goes through a loop the compiler vectorizes.
template <typename P>
__attribute__((always_inline)) inline void CodesRun(const MortonGrid& g, const RecordFrame& f, const P* points,
                                                    size_t n, uint64_t* codes) {
  constexpr size_t kBlock = 256;
  decltype(P::x) xs[kBlock], ys[kBlock], zs[kBlock];
  uint64_t sx[kBlock], sy[kBlock], sz[kBlock];
  for (size_t base = 0; base < n; base += kBlock) {
    const size_t m = std::min(kBlock, n - base);
    for (size_t i = 0; i < m; ++i) {
      xs[i] = points[base + i].x;
      ys[i] = points[base + i].y;
      zs[i] = points[base + i].z;
    }
    SpreadAxisOf<P>(xs, m, f, 0, g, sx);
    SpreadAxisOf<P>(ys, m, f, 1, g, sy);
    SpreadAxisOf<P>(zs, m, f, 2, g, sz);
    for (size_t i = 0; i < m; ++i) codes[base + i] = sx[i] | sy[i] << 1 | sz[i] << 2;
  }
}

}  // namespace

#define CANDI_PACK_RECORD_KERNELS(P)                                                                     \
  CANDI_TARGET_CLONES_AVX2                                                                               \
  void MortonCodes(const MortonGrid& g, const RecordFrame& f, const P* points, size_t n, uint64_t* codes) { \
    CodesRun(g, f, points, n, codes);                                                                    \
  }                                                                                                      \
  CANDI_TARGET_CLONES_AVX2                                                                               \
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

#include "render/pack_records.h"

#include <algorithm>
#include <type_traits>

#include "core/simd.h"

namespace candi::render::pack_internal {

namespace {

template <typename P>
inline void EncodeRun(const ChunkQuantizer& q, const Eigen::Vector3d& shift, const P* points, size_t n,
                      uint64_t* words) {
  for (size_t i = 0; i < n; ++i) words[i] = q.Encode(points[i].Position(shift), points[i].rgb);
}

// Spread(quantized coordinate) of c[0, m) on one axis: Quantize's operations on doubles.
template <typename T>
__attribute__((always_inline)) inline void SpreadAxis(const T* __restrict c, size_t m, double shift, double lo, double scale,
                       uint64_t* __restrict out) {
  const double top = static_cast<double>((1 << kMortonBits) - 1);
  for (size_t i = 0; i < m; ++i) {
    double v = (double{c[i]} + shift - lo) * scale;
    v = v < 0.0 ? 0.0 : v;  // std::clamp(v, 0.0, top)
    v = top < v ? top : v;
    out[i] = Spread(static_cast<uint64_t>(static_cast<int32_t>(v)));
  }
}

// MortonGrid::Code of points[0, n), in blocks: the coordinates are copied out per axis, then each
// axis goes through a loop the compiler vectorizes.
template <typename P>
__attribute__((always_inline)) inline void CodesRun(const MortonGrid& g, const Eigen::Vector3d& shift, const P* points, size_t n, uint64_t* codes) {
  constexpr size_t kBlock = 256;
  using T = decltype(P::x);
  const bool shifted = std::is_same_v<P, CompactPoint>;  // WidePoint::Position ignores the shift
  T xs[kBlock], ys[kBlock], zs[kBlock];
  uint64_t sx[kBlock], sy[kBlock], sz[kBlock];
  for (size_t base = 0; base < n; base += kBlock) {
    const size_t m = std::min(kBlock, n - base);
    for (size_t i = 0; i < m; ++i) {
      xs[i] = points[base + i].x;
      ys[i] = points[base + i].y;
      zs[i] = points[base + i].z;
    }
    SpreadAxis(xs, m, shifted ? shift[0] : 0.0, g.min[0], g.scale[0], sx);
    SpreadAxis(ys, m, shifted ? shift[1] : 0.0, g.min[1], g.scale[1], sy);
    SpreadAxis(zs, m, shifted ? shift[2] : 0.0, g.min[2], g.scale[2], sz);
    for (size_t i = 0; i < m; ++i) codes[base + i] = sx[i] | sy[i] << 1 | sz[i] << 2;
  }
}

}  // namespace

CANDI_TARGET_CLONES_AVX2
void MortonCodes(const MortonGrid& g, const Eigen::Vector3d& shift, const CompactPoint* points, size_t n,
                 uint64_t* codes) {
  CodesRun(g, shift, points, n, codes);
}

CANDI_TARGET_CLONES_AVX2
void MortonCodes(const MortonGrid& g, const Eigen::Vector3d& shift, const WidePoint* points, size_t n,
                 uint64_t* codes) {
  CodesRun(g, shift, points, n, codes);
}

CANDI_TARGET_CLONES_AVX2
void Encode(const ChunkQuantizer& q, const Eigen::Vector3d& shift, const WidePoint* points, size_t n,
            uint64_t* words) {
  EncodeRun(q, shift, points, n, words);
}

CANDI_TARGET_CLONES_AVX2
void Encode(const ChunkQuantizer& q, const Eigen::Vector3d& shift, const CompactPoint* points, size_t n,
            uint64_t* words) {
  EncodeRun(q, shift, points, n, words);
}

}  // namespace candi::render::pack_internal

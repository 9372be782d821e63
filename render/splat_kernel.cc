#include "render/splat_kernel.h"

#include <cstring>

#include "core/simd.h"

namespace candi::render {

void BandBuffer::Reset(int w, int r) {
  width = w;
  rows = r;
  keys.assign(static_cast<size_t>(w) * r + 1, kEmptyKey);
  keys.back() = 0;  // the spare slot
  filled.resize(static_cast<size_t>(w) * r + 256);
  filled_count = 0;
}

namespace {

constexpr size_t kBatch = 256;

// Phase 1, vectorizable: camera coordinates, the pixel in the band (the spare slot when off the
// band, behind the near plane or NaN) and the key: the depth's float bits (positive depths order
// as their bits) above the colour.
template <bool kPerspective, typename T>
__attribute__((always_inline)) inline void ProjectBatch(const KernelTransform& t, const KernelProjection& p, uint32_t spare,
                  const T* __restrict x, const T* __restrict y, const T* __restrict z,
                  const uint32_t* __restrict colors, size_t n, uint32_t* __restrict pixel,
                  uint64_t* __restrict key) {
  // Everything in locals: the outputs are arrays the compiler would otherwise assume to alias
  // the parameters, which keeps it from vectorizing.
  const float a0 = t.a[0], a1 = t.a[1], a2 = t.a[2], a3 = t.a[3], a4 = t.a[4], a5 = t.a[5];
  const float a6 = t.a[6], a7 = t.a[7], a8 = t.a[8], b0 = t.b[0], b1 = t.b[1], b2 = t.b[2];
  const float focal = p.focal, ou = p.cx, ov = p.cy, near = p.near;
  const float w = static_cast<float>(p.width);
  const float r0 = static_cast<float>(p.row0), r1 = static_cast<float>(p.row1);
  const int width = p.width, row0 = p.row0;
  float depth[kBatch];
  for (size_t i = 0; i < n; ++i) {
    const float X = static_cast<float>(x[i]), Y = static_cast<float>(y[i]), Z = static_cast<float>(z[i]);
    const float cx = a0 * X + a1 * Y + a2 * Z + b0;
    const float cy = a3 * X + a4 * Y + a5 * Z + b1;
    const float cz = a6 * X + a7 * Y + a8 * Z + b2;
    const float s = kPerspective ? focal / cz : focal;
    const float u = ou + s * cx, v = ov + s * cy;
    // Non-short-circuit '&': every lane computes every test (NaN fails them all).
    const bool valid = (cz > near) & (u >= 0.0f) & (u < w) & (v >= r0) & (v < r1);
    // Clamped before converting: a float outside int's range must not reach the conversion.
    const int iu = static_cast<int>(std::min(std::max(u, 0.0f), w - 1.0f));
    const int iv = static_cast<int>(std::min(std::max(v, r0), r1 - 1.0f)) - row0;
    pixel[i] = valid ? static_cast<uint32_t>(iv * width + iu) : spare;
    depth[i] = cz;
  }
  for (size_t i = 0; i < n; ++i) {
    uint32_t bits;
    std::memcpy(&bits, &depth[i], sizeof(bits));
    key[i] = static_cast<uint64_t>(bits) << 32 | colors[i];
  }
}

// Phase 2, branch-free: keep the smaller key; list pixels drawn for the first time (the spare
// slot holds key 0, so it is never listed). Morton-ordered points often hit the pixel of the point
// before, and each such test would wait for the previous store; four interleaved quarters of the
// batch keep four independent chains in flight. The order of the tests does not change the
// result (min is commutative; the filled list is only summed).
__attribute__((always_inline)) inline void TestOne(uint32_t p, uint64_t k, uint64_t* __restrict keys,
                                                   uint32_t* __restrict filled, size_t* count) {
  const uint64_t old = keys[p];
  keys[p] = k < old ? k : old;
  filled[*count] = p;
  *count += old == kEmptyKey;
}

__attribute__((always_inline)) inline void TestBatch(const uint32_t* __restrict pixel, const uint64_t* __restrict key,
                                                     size_t n, BandBuffer* band) {
  uint64_t* keys = band->keys.data();
  uint32_t* filled = band->filled.data();
  size_t count = band->filled_count;
  const size_t q = n / 4;
  for (size_t i = 0; i < q; ++i) {
    TestOne(pixel[i], key[i], keys, filled, &count);
    TestOne(pixel[i + q], key[i + q], keys, filled, &count);
    TestOne(pixel[i + 2 * q], key[i + 2 * q], keys, filled, &count);
    TestOne(pixel[i + 3 * q], key[i + 3 * q], keys, filled, &count);
  }
  for (size_t i = 4 * q; i < n; ++i) TestOne(pixel[i], key[i], keys, filled, &count);
  band->filled_count = count;
}

// The whole point loop is compiled twice: for AVX2 (8 lanes in phase 1) and for the baseline
// (SSE2), chosen at load time by the CPU. Both give the same bits: no FMA contraction (ISO C++
// mode), and vector division and conversion are exact IEEE operations as in scalar code.
template <typename T>
__attribute__((always_inline)) inline void SplatLoop(const KernelTransform& t, const KernelProjection& p,
                                                      const T* x, const T* y, const T* z,
                                                      const uint32_t* colors, size_t n, BandBuffer* band) {
  uint32_t pixel[kBatch];
  uint64_t key[kBatch];
  for (size_t s = 0; s < n; s += kBatch) {
    const size_t m = std::min(kBatch, n - s);
    if (p.perspective) {
      ProjectBatch<true>(t, p, band->spare(), x + s, y + s, z + s, colors + s, m, pixel, key);
    } else {
      ProjectBatch<false>(t, p, band->spare(), x + s, y + s, z + s, colors + s, m, pixel, key);
    }
    TestBatch(pixel, key, m, band);
  }
}

CANDI_TARGET_CLONES_AVX2
void SplatLoopU16(const KernelTransform& t, const KernelProjection& p, const uint16_t* x, const uint16_t* y,
                  const uint16_t* z, const uint32_t* colors, size_t n, BandBuffer* band) {
  SplatLoop(t, p, x, y, z, colors, n, band);
}

CANDI_TARGET_CLONES_AVX2
void SplatLoopF32(const KernelTransform& t, const KernelProjection& p, const float* x, const float* y,
                  const float* z, const uint32_t* colors, size_t n, BandBuffer* band) {
  SplatLoop(t, p, x, y, z, colors, n, band);
}

// A footprint centred on (u, v), clipped to the band: a side x side square, or the pixels whose
// centres lie within disc_radius when that is > 0.
void SplatFootprint(const KernelProjection& p, float u, float v, int side, float disc_radius,
                    uint64_t key, BandBuffer* band) {
  int x0, x1, y0, y1;  // inclusive pixel ranges before clipping
  if (disc_radius > 0.0f) {
    x0 = static_cast<int>(std::floor(u - disc_radius));
    x1 = static_cast<int>(std::floor(u + disc_radius));
    y0 = static_cast<int>(std::floor(v - disc_radius));
    y1 = static_cast<int>(std::floor(v + disc_radius));
  } else {
    x0 = static_cast<int>(std::floor(u - 0.5f * side + 0.5f));
    y0 = static_cast<int>(std::floor(v - 0.5f * side + 0.5f));
    x1 = x0 + side - 1;
    y1 = y0 + side - 1;
  }
  x0 = std::max(x0, 0), x1 = std::min(x1, p.width - 1);
  y0 = std::max(y0, p.row0), y1 = std::min(y1, p.row1 - 1);
  const float r2 = disc_radius * disc_radius;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      if (disc_radius > 0.0f) {
        const float dx = x + 0.5f - u, dy = y + 0.5f - v;
        if (dx * dx + dy * dy > r2) continue;
      }
      const uint32_t q = static_cast<uint32_t>((y - p.row0) * p.width + x);
      uint64_t& slot = band->keys[q];
      if (slot == kEmptyKey) band->filled[band->filled_count++] = q;
      slot = std::min(slot, key);
    }
  }
}

template <typename T>
void SplatPointsSizedImpl(const KernelTransform& t, const KernelProjection& p, const T* x,
                          const T* y, const T* z, const uint32_t* colors, size_t n,
                          const SizedSplat& sized, BandBuffer* band) {
  const int k = static_cast<int>(std::floor(sized.size));
  const double f = sized.size - k;
  const double p_up = f * (2 * k + f) / (2 * k + 1);
  const bool disc = sized.size > 3.0;
  const float radius = disc ? static_cast<float>(sized.size / std::sqrt(M_PI)) : 0.0f;
  for (size_t i = 0; i < n; ++i) {
    const float X = static_cast<float>(x[i]), Y = static_cast<float>(y[i]), Z = static_cast<float>(z[i]);
    const float cx = t.a[0] * X + t.a[1] * Y + t.a[2] * Z + t.b[0];
    const float cy = t.a[3] * X + t.a[4] * Y + t.a[5] * Z + t.b[1];
    const float cz = t.a[6] * X + t.a[7] * Y + t.a[8] * Z + t.b[2];
    if (!(cz > p.near)) continue;
    const float s = p.perspective ? p.focal / cz : p.focal;
    const float u = p.cx + s * cx, v = p.cy + s * cy;
    if (!(std::abs(u) < 1e7f && std::abs(v) < 1e7f)) continue;
    const bool up = !disc && ToUnit(HashIndex(sized.seed, sized.first_index + i, 0x5157)) < p_up;
    uint32_t bits;
    std::memcpy(&bits, &cz, sizeof(bits));
    SplatFootprint(p, u, v, k + (up ? 1 : 0), radius, static_cast<uint64_t>(bits) << 32 | colors[i], band);
  }
}

}  // namespace

void SplatPoints(const KernelTransform& t, const KernelProjection& p, const uint16_t* x,
                 const uint16_t* y, const uint16_t* z, const uint32_t* colors, size_t n, BandBuffer* band) {
  SplatLoopU16(t, p, x, y, z, colors, n, band);
}
void SplatPoints(const KernelTransform& t, const KernelProjection& p, const float* x,
                 const float* y, const float* z, const uint32_t* colors, size_t n, BandBuffer* band) {
  SplatLoopF32(t, p, x, y, z, colors, n, band);
}
void SplatPointsSized(const KernelTransform& t, const KernelProjection& p, const uint16_t* x,
                      const uint16_t* y, const uint16_t* z, const uint32_t* colors, size_t n,
                      const SizedSplat& sized, BandBuffer* band) {
  SplatPointsSizedImpl(t, p, x, y, z, colors, n, sized, band);
}
void SplatPointsSized(const KernelTransform& t, const KernelProjection& p, const float* x,
                      const float* y, const float* z, const uint32_t* colors, size_t n,
                      const SizedSplat& sized, BandBuffer* band) {
  SplatPointsSizedImpl(t, p, x, y, z, colors, n, sized, band);
}

}  // namespace candi::render

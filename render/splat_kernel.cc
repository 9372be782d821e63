#include "render/splat_kernel.h"

#include <sys/mman.h>
#include <unistd.h>

#include <cstring>
#include <new>

#include "core/check.h"
#include "core/simd.h"

#ifndef MADV_POPULATE_WRITE
#define MADV_POPULATE_WRITE 23  // Linux 5.14
#endif

namespace candi::render {

namespace {

// Drains the slots list[0, n): adds each slot's key (key_of(stored)) to the sums of its pixel
// (pixel_of(slot)), counts its grey level when `grey` is given, and stores `empty` in it. The
// sums of an ensemble's pixels lie scattered over a 16-byte-per-pixel frame, so the loads would
// wait on cache misses in turn: the pixel of the slot kAhead places on is computed first, kept in
// a ring, and its sums and key prefetched (~20 % of a 10^7-point frame at L = 100).
template <typename PixelOf, typename KeyOf>
void DrainSlots(uint64_t* keys, const uint32_t* list, size_t n, uint64_t empty, PixelOf pixel_of, KeyOf key_of,
                Accumulator* sums, GreyHistogram* grey) {
  constexpr size_t kAhead = 64;
  uint32_t ring[kAhead];
  uint32_t* s = sums->sums.data();
  const size_t lead = std::min(n, kAhead);
  for (size_t i = 0; i < lead; ++i) ring[i] = pixel_of(list[i]);
  for (size_t i = 0; i < n; ++i) {
    const uint32_t slot = list[i];
    const uint32_t pixel = ring[i % kAhead];
    if (i + kAhead < n) {
      const uint32_t next = list[i + kAhead];
      const uint32_t p = pixel_of(next);
      ring[i % kAhead] = p;
      __builtin_prefetch(&s[4 * size_t{p}], 1);
      __builtin_prefetch(&keys[next], 1);
    }
    const uint64_t key = key_of(keys[slot]);
    sums->Add(pixel, key);
    if (grey) ++(*grey)[KeyGrey(key)];
    keys[slot] = empty;
  }
}

}  // namespace

void BandBuffer::DrainInto(Accumulator* sums, GreyHistogram* grey) {
  DrainSlots(keys.data(), filled.data(), filled_count, kEmptyKey, [](uint32_t slot) { return slot; },
             [](uint64_t key) { return key; }, sums, grey);
  filled_count = 0;
}

void EnsembleBuffers::DrainInto(int k, Accumulator* sums, GreyHistogram* grey) {
  DrainSlots(keys(k), filled(k), counts_[k], 0, [this](uint32_t slot) { return PixelOf(slot); },
             [](uint64_t key) { return ~key; }, sums, grey);
  counts_[k] = 0;
}

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
// With kTiled, the pixel index is EnsembleBuffers' tiled one (tiles_x tiles a row of tiles).
template <bool kPerspective, bool kTiled = false, typename T>
__attribute__((always_inline)) inline void ProjectBatch(const KernelTransform& t, const KernelProjection& p, uint32_t spare,
                  const T* __restrict x, const T* __restrict y, const T* __restrict z,
                  const uint32_t* __restrict colors, size_t n, uint32_t* __restrict pixel,
                  uint64_t* __restrict key, uint32_t tiles_x = 0) {
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
    const uint32_t index = kTiled ? EnsembleBuffers::TiledIndex(iu, iv, tiles_x) : static_cast<uint32_t>(iv * width + iu);
    pixel[i] = valid ? index : spare;
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

// Calls f(x, row_in_band) for each pixel of a footprint centred on (u, v), clipped to the band: a
// side x side square, or the pixels whose centres lie within disc_radius when that is > 0.
template <typename F>
inline void ForFootprint(const KernelProjection& p, float u, float v, int side, float disc_radius, F&& f) {
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
      f(x, y - p.row0);
    }
  }
}

// The stochastic rounding of a point size (see SizedSplat).
struct SizedShape {
  int k;          // whole pixels
  double p_up;    // probability of a (k+1)-pixel square
  bool disc;      // above 3 pixels: a disc of `radius`
  float radius;
  explicit SizedShape(double size)
      : k(static_cast<int>(std::floor(size))),
        p_up((size - k) * (2 * k + (size - k)) / (2 * k + 1)),
        disc(size > 3.0),
        radius(disc ? static_cast<float>(size / std::sqrt(M_PI)) : 0.0f) {}
};

// One sized point: calls f(x, row_in_band, key) for each pixel of its footprint.
template <typename F>
inline void SplatSizedOne(const KernelTransform& t, const KernelProjection& p, float X, float Y, float Z,
                          uint32_t color, const SizedShape& shape, uint64_t seed, uint64_t index, F&& f) {
  const float cx = t.a[0] * X + t.a[1] * Y + t.a[2] * Z + t.b[0];
  const float cy = t.a[3] * X + t.a[4] * Y + t.a[5] * Z + t.b[1];
  const float cz = t.a[6] * X + t.a[7] * Y + t.a[8] * Z + t.b[2];
  if (!(cz > p.near)) return;
  const float s = p.perspective ? p.focal / cz : p.focal;
  const float u = p.cx + s * cx, v = p.cy + s * cy;
  if (!(std::abs(u) < 1e7f && std::abs(v) < 1e7f)) return;
  const bool up = !shape.disc && ToUnit(HashIndex(seed, index, 0x5157)) < shape.p_up;
  uint32_t bits;
  std::memcpy(&bits, &cz, sizeof(bits));
  const uint64_t key = static_cast<uint64_t>(bits) << 32 | color;
  ForFootprint(p, u, v, shape.k + (up ? 1 : 0), shape.radius, [&](int x, int y) { f(x, y, key); });
}

template <typename T>
void SplatPointsSizedImpl(const KernelTransform& t, const KernelProjection& p, const T* x,
                          const T* y, const T* z, const uint32_t* colors, size_t n,
                          const SizedSplat& sized, BandBuffer* band) {
  const SizedShape shape(sized.size);
  for (size_t i = 0; i < n; ++i) {
    SplatSizedOne(t, p, static_cast<float>(x[i]), static_cast<float>(y[i]), static_cast<float>(z[i]), colors[i],
                  shape, sized.seed, sized.first_index + i, [&](int x, int y, uint64_t key) {
                    const uint32_t q = static_cast<uint32_t>(y * p.width + x);
                    uint64_t& slot = band->keys[q];
                    if (slot == kEmptyKey) band->filled[band->filled_count++] = q;
                    slot = std::min(slot, key);
                  });
  }
}

// Exact conversion of an integer below 2^52 to double, in integer and double operations that
// vectorize (AVX2 has no 64-bit integer conversion): the value placed in the mantissa of 2^52.
inline double SmallU64ToDouble(uint64_t q) {
  const uint64_t bits = q | 0x4330000000000000ULL;
  double d;
  std::memcpy(&d, &bits, sizeof(d));
  return d - 4503599627370496.0;  // 2^52
}

// The inverted z-test (EnsembleBuffers): keep the larger stored value; list pixels drawn first.
__attribute__((always_inline)) inline void TestInverted(uint32_t p, uint64_t stored, uint64_t* __restrict keys,
                                                        uint32_t* __restrict filled, size_t* count) {
  const uint64_t old = keys[p];
  keys[p] = stored > old ? stored : old;
  filled[*count] = p;
  *count += old == 0;
}

// The points of a batch whose ensemble (the seeded hash of the archive index, scaled by L) is
// one of [first, first + K): their positions in the batch and their ensembles - first.
// Positions (ChunkQuantizer::Decode, then float) and colours of the chosen words.
__attribute__((always_inline)) inline void DecodeBatch(const QuantizedPoints& in, const uint64_t* __restrict words,
                                                       const uint32_t* __restrict chosen, size_t m, float* __restrict x,
                                                       float* __restrict y, float* __restrict z,
                                                       uint32_t* __restrict color) {
  const int b0 = in.bits[0], b1 = in.bits[1];
  const uint64_t m0 = (uint64_t{1} << in.bits[0]) - 1, m1 = (uint64_t{1} << in.bits[1]) - 1;
  const uint64_t m2 = (uint64_t{1} << in.bits[2]) - 1;
  const double min0 = in.min[0], min1 = in.min[1], min2 = in.min[2];
  const double s0 = in.step[0], s1 = in.step[1], s2 = in.step[2];
  for (size_t j = 0; j < m; ++j) {
    const uint64_t w = words[chosen[j]];
    const uint64_t q = w >> 24;
    x[j] = static_cast<float>(min0 + SmallU64ToDouble(q & m0) * s0);
    y[j] = static_cast<float>(min1 + SmallU64ToDouble((q >> b0) & m1) * s1);
    z[j] = static_cast<float>(min2 + SmallU64ToDouble((q >> (b0 + b1)) & m2) * s2);
    color[j] = static_cast<uint32_t>(w & 0xffffff);
  }
}

// The points of a batch inside the clip region (ClipRegion::Contains of the position
// ChunkQuantizer::Decode gives: the same expression, so every renderer keeps the same points):
// their positions in the batch, in order, into `chosen`; returns how many.
inline size_t ClipBatch(const QuantizedPoints& in, const uint64_t* words, size_t n, uint32_t* chosen) {
  const int b0 = in.bits[0], b1 = in.bits[1];
  const uint64_t m0 = (uint64_t{1} << in.bits[0]) - 1, m1 = (uint64_t{1} << in.bits[1]) - 1;
  const uint64_t m2 = (uint64_t{1} << in.bits[2]) - 1;
  size_t m = 0;
  for (size_t j = 0; j < n; ++j) {
    const uint64_t q = words[j] >> 24;
    const Eigen::Vector3d x(in.min[0] + static_cast<double>(q & m0) * in.step[0],
                            in.min[1] + static_cast<double>((q >> b0) & m1) * in.step[1],
                            in.min[2] + static_cast<double>((q >> (b0 + b1)) & m2) * in.step[2]);
    chosen[m] = static_cast<uint32_t>(j);
    m += in.clip->Contains(x) ? 1 : 0;
  }
  return m;
}

template <bool kPerspective>
__attribute__((always_inline)) inline uint64_t SplatQuantizedLoop(const KernelTransform& t, const KernelProjection& p,
                                                                   const QuantizedPoints& in,
                                                                   const EnsembleSelection& sel, EnsembleBuffers* out) {
  const uint32_t spare = out->spare(), tiles_x = out->tiles_x();
  const SizedShape shape(sel.point_size);
  uint64_t* keys = out->keys(sel.base);
  uint32_t* filled = out->filled(sel.base);
  size_t* count = out->counts() + sel.base;
  uint32_t chosen[kBatch], color[kBatch], pixel[kBatch];
  for (uint32_t i = 0; i < kBatch; ++i) chosen[i] = i;
  float x[kBatch], y[kBatch], z[kBatch];
  uint64_t key[kBatch];
  uint64_t drawn = 0;
  for (uint64_t s = 0; s < in.count; s += kBatch) {
    size_t n = static_cast<size_t>(std::min<uint64_t>(kBatch, in.count - s));
    const uint64_t index0 = in.first_index + s;
    if (in.clip != nullptr) n = ClipBatch(in, in.words + s, n, chosen);
    drawn += n;
    DecodeBatch(in, in.words + s, chosen, n, x, y, z, color);
    if (sel.point_size != 1.0) {
      for (size_t j = 0; j < n; ++j) {
        SplatSizedOne(t, p, x[j], y[j], z[j], color[j], shape, sel.seed, index0 + chosen[j],
                      [&](int px, int py, uint64_t k64) {
                        const uint32_t q = EnsembleBuffers::TiledIndex(px, py, tiles_x);
                        const uint64_t old = keys[q];
                        if (old == 0) filled[(*count)++] = q;
                        keys[q] = std::max(old, ~k64);
                      });
      }
      continue;
    }
    ProjectBatch<kPerspective, true>(t, p, spare, x, y, z, color, n, pixel, key, tiles_x);
    for (size_t j = 0; j < n; ++j) TestInverted(pixel[j], ~key[j], keys, filled, count);
  }
  return drawn;
}

CANDI_TARGET_CLONES_AVX2
uint64_t SplatQuantizedImpl(const KernelTransform& t, const KernelProjection& p, const QuantizedPoints& in,
                            const EnsembleSelection& sel, EnsembleBuffers* out) {
  return p.perspective ? SplatQuantizedLoop<true>(t, p, in, sel, out) : SplatQuantizedLoop<false>(t, p, in, sel, out);
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

uint64_t SplatQuantized(const KernelTransform& t, const KernelProjection& p, const QuantizedPoints& points,
                        const EnsembleSelection& selection, EnsembleBuffers* buffers) {
  CANDI_CHECK(selection.base >= 0 && selection.base < buffers->ensembles());
  CANDI_CHECK(p.row0 == 0 && p.row1 == buffers->height() && p.width == buffers->width());
  return SplatQuantizedImpl(t, p, points, selection, buffers);
}

EnsembleBuffers::EnsembleBuffers(int width, int height, int ensembles)
    : ensembles_(ensembles),
      width_(width),
      height_(height),
      tiles_x_(static_cast<uint32_t>((width + kTileWidth - 1) / kTileWidth)),
      pixels_(static_cast<size_t>(tiles_x_) * ((height + kTileHeight - 1) / kTileHeight) * kTileWidth * kTileHeight),
      counts_(ensembles, 0),
      prepared_(ensembles, 0) {
  CANDI_CHECK_LT(0, ensembles);
  key_bytes_ = sizeof(uint64_t) * stride() * ensembles;
  filled_bytes_ = sizeof(uint32_t) * stride() * ensembles;
  // Anonymous mappings are zero pages until written: no fill, and untouched pages cost nothing.
  const int flags = MAP_PRIVATE | MAP_ANONYMOUS;
  void* k = mmap(nullptr, key_bytes_, PROT_READ | PROT_WRITE, flags, -1, 0);
  if (k == MAP_FAILED) throw std::bad_alloc();
  void* f = mmap(nullptr, filled_bytes_, PROT_READ | PROT_WRITE, flags, -1, 0);
  if (f == MAP_FAILED) {
    munmap(k, key_bytes_);
    throw std::bad_alloc();
  }
  keys_ = static_cast<uint64_t*>(k);
  filled_ = static_cast<uint32_t*>(f);
  for (int e = 0; e < ensembles; ++e) keys(e)[pixels_] = ~uint64_t{0};  // the spare slots
  tile_origin_.resize(pixels_ / (kTileWidth * kTileHeight));
  for (uint32_t t = 0; t < tile_origin_.size(); ++t) {
    tile_origin_[t] = (t / tiles_x_) * kTileHeight * static_cast<uint32_t>(width) + (t % tiles_x_) * kTileWidth;
  }
}

void EnsembleBuffers::Prepare(int begin, int end) {
  CANDI_CHECK(begin >= 0 && begin <= end && end <= ensembles_);
  while (begin < end && prepared_[begin]) ++begin;
  while (end > begin && prepared_[end - 1]) --end;
  if (begin == end) return;
  const uintptr_t page = static_cast<uintptr_t>(sysconf(_SC_PAGESIZE));
  auto populate = [&](void* from, void* to) {
    const uintptr_t a = reinterpret_cast<uintptr_t>(from) / page * page;
    const uintptr_t b = (reinterpret_cast<uintptr_t>(to) + page - 1) / page * page;
    if (madvise(reinterpret_cast<void*>(a), b - a, MADV_POPULATE_WRITE) != 0) {
      // Kernels before 5.14: a write to each page that changes nothing (an atomic or of 0 is a
      // write fault, so no zero page; other threads may be drawing on a shared boundary page).
      for (uintptr_t q = a; q < b; q += page) __atomic_fetch_or(reinterpret_cast<uint8_t*>(q), 0, __ATOMIC_RELAXED);
    }
  };
  populate(keys(begin), keys(end));
  populate(filled(begin), filled(end));
  for (int k = begin; k < end; ++k) prepared_[k] = 1;
}

void EnsembleBuffers::Absorb(int k, EnsembleBuffers* other) {
  CANDI_CHECK(other->width_ == width_ && other->height_ == height_ && k < ensembles_ && k < other->ensembles_);
  uint64_t* mine = keys(k);
  uint64_t* theirs = other->keys(k);
  uint32_t* list = filled(k);
  const uint32_t* their_list = other->filled(k);
  size_t count = counts_[k];
  for (size_t i = 0; i < other->counts_[k]; ++i) {  // slots: the same layout in both
    const uint32_t slot = their_list[i];
    const uint64_t old = mine[slot];
    if (old == 0) list[count++] = slot;
    mine[slot] = std::max(old, theirs[slot]);
    theirs[slot] = 0;
  }
  counts_[k] = count;
  other->counts_[k] = 0;
}

EnsembleBuffers::~EnsembleBuffers() {
  munmap(keys_, key_bytes_);
  munmap(filled_, filled_bytes_);
}


}  // namespace candi::render

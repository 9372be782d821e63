// The SPBR splat kernel: project a batch of points and keep the nearest per pixel of a band.
//
// The renderer splits the image into bands of rows; a band's key buffer (8 bytes per pixel, plus
// one spare slot that absorbs off-band points) fits in the L2 cache, so z-tests do not go to
// memory. Per batch of 256 points: a branch-free loop that transforms, projects and computes
// pixel indices and keys (the compiler vectorizes it), then a branch-free z-test loop that also
// lists the pixels an ensemble fills first, so draining an ensemble costs what it drew.
// Positions come as three arrays (x, y, z) of uint16 (quantized blocks) or float; the transform
// maps them to camera coordinates: c = A * (x, y, z) + b.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/rng.h"
#include "render/frame.h"

namespace candi::render {

// Camera coordinates of the kernel's input: c = A p + b (row-major A).
struct KernelTransform {
  float a[9];
  float b[3];
};

// Pixel mapping: u = cx + focal * c.x / c.z (perspective) or cx + focal * c.x, and the band of
// rows [row0, row1) being drawn. Depths c.z of drawn points must be positive (orthographic
// views shift them): the kernel's keys use the float's bits, which order positive floats.
struct KernelProjection {
  float focal, cx, cy, near;
  bool perspective;
  int width, height;
  int row0, row1;
};

// The keys of one band: width * rows pixels and one spare slot, plus the pixels filled since the
// last drain. The spare slot absorbs the points that miss the band and holds key 0, so it is
// never "empty" and never listed. Not thread-safe.
struct BandBuffer {
  int width = 0, rows = 0;
  std::vector<uint64_t> keys;     // width * rows + 1; the last is the spare slot
  std::vector<uint32_t> filled;   // pixels that went from empty to drawn
  size_t filled_count = 0;
  void Reset(int w, int r);
  uint32_t spare() const { return static_cast<uint32_t>(width * rows); }
  // Calls f(pixel_in_band, key) for every drawn pixel and empties them: cost ~ pixels drawn.
  template <typename F>
  void Drain(F&& f) {
    for (size_t i = 0; i < filled_count; ++i) {
      const uint32_t p = filled[i];
      f(p, keys[p]);
      keys[p] = kEmptyKey;
    }
    filled_count = 0;
  }
};

// Splats n one-pixel points (positions x, y, z; colours 0x00RRGGBB) into the band.
void SplatPoints(const KernelTransform& t, const KernelProjection& p, const uint16_t* x,
                 const uint16_t* y, const uint16_t* z, const uint32_t* colors, size_t n, BandBuffer* band);
void SplatPoints(const KernelTransform& t, const KernelProjection& p, const float* x,
                 const float* y, const float* z, const uint32_t* colors, size_t n, BandBuffer* band);

// Point sizes above one pixel. A size s = k + f (k whole pixels) is drawn as a (k+1)-pixel square
// with probability f(2k + f) / (2k + 1), else as a k-pixel square, so the expected area is s^2
// (KVS's stochastic rounding); above 3 pixels an equal-area disc of radius s / sqrt(pi). The
// draw for point i uses HashIndex(seed, first_index + i): seeded and independent of the order.
struct SizedSplat {
  double size = 1.0;
  uint64_t seed = 0;
  uint64_t first_index = 0;
};
void SplatPointsSized(const KernelTransform& t, const KernelProjection& p, const uint16_t* x,
                      const uint16_t* y, const uint16_t* z, const uint32_t* colors, size_t n,
                      const SizedSplat& sized, BandBuffer* band);
void SplatPointsSized(const KernelTransform& t, const KernelProjection& p, const float* x,
                      const float* y, const float* z, const uint32_t* colors, size_t n,
                      const SizedSplat& sized, BandBuffer* band);

}  // namespace candi::render

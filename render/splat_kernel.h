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

#include "core/clip.h"
#include "core/rng.h"
#include "render/frame.h"
#include "render/splat_cloud.h"

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
  UninitVector<uint32_t> filled;  // pixels that went from empty to drawn (no zero fill: pages
                                  // a stream render's ensembles never reach stay unmapped)
  size_t filled_count = 0;
  void Reset(int w, int r);
  uint32_t spare() const { return static_cast<uint32_t>(width * rows); }
  // Adds every drawn pixel's colour to `sums` (pixel p of the band is pixel p of `sums`: a band
  // of the whole image), counts its grey level in `grey` when given, and empties the pixels:
  // cost ~ pixels drawn.
  void DrainInto(Accumulator* sums, GreyHistogram* grey);
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

// The resident ensembles of the archive renderer. Keys are stored inverted (~key: 0 is empty and
// the nearest point holds the largest value), so the buffers are fresh anonymous pages, zero
// without a fill. Pixels are stored in tiles of 32 x 16 (one 4 KB page of keys), so the compact
// screen footprint of a chunk's points touches few pages of each ensemble. Per ensemble: stride()
// key slots, the whole tiles then the spare slot (holding ~0: never empty, never listed), and the
// slots drawn since the last drain. Threads may draw different ensembles at once.
class EnsembleBuffers {
 public:
  EnsembleBuffers(int width, int height, int ensembles);
  ~EnsembleBuffers();
  EnsembleBuffers(const EnsembleBuffers&) = delete;
  EnsembleBuffers& operator=(const EnsembleBuffers&) = delete;

  static constexpr int kTileWidth = 32, kTileHeight = 16;
  // The slot of pixel (x, y) when a row of tiles holds tiles_x of them.
  static uint32_t TiledIndex(int x, int y, uint32_t tiles_x) {
    const uint32_t tile = static_cast<uint32_t>(y / kTileHeight) * tiles_x + static_cast<uint32_t>(x / kTileWidth);
    return tile * (kTileWidth * kTileHeight) + static_cast<uint32_t>((y % kTileHeight) * kTileWidth + x % kTileWidth);
  }
  // The row-major pixel y * width + x of a slot.
  uint32_t PixelOf(uint32_t slot) const {
    const uint32_t within = slot % (kTileWidth * kTileHeight);
    return tile_origin_[slot / (kTileWidth * kTileHeight)] + (within / kTileWidth) * static_cast<uint32_t>(width_) +
           within % kTileWidth;
  }

  int ensembles() const { return ensembles_; }
  int width() const { return width_; }
  int height() const { return height_; }
  uint32_t tiles_x() const { return tiles_x_; }
  uint32_t spare() const { return static_cast<uint32_t>(pixels_); }
  // Slots from one ensemble to the next: whole tiles plus one for the spare slot, so every
  // ensemble's keys start on a page.
  size_t stride() const { return pixels_ + kTileWidth * kTileHeight; }
  uint64_t* keys(int k) { return keys_ + static_cast<size_t>(k) * stride(); }
  uint32_t* filled(int k) { return filled_ + static_cast<size_t>(k) * stride(); }
  size_t* counts() { return counts_.data(); }
  // Faults in ensembles [begin, end) writable, so that drawing them takes no page faults: a
  // first read of a fresh page would map the shared zero page, and the write after it would
  // then replace it and make the kernel flush the TLBs of every thread of the process. Call it
  // from the thread that draws them; ensembles already prepared are skipped.
  void Prepare(int begin, int end);
  // Moves ensemble k of `other` (the same size) into this one's, the nearer key per pixel, and
  // empties other's.
  void Absorb(int k, EnsembleBuffers* other);
  // Adds the colour of every pixel ensemble k drew to `sums`, counts its grey level in `grey`
  // when given, and empties the pixels: cost ~ pixels drawn.
  void DrainInto(int k, Accumulator* sums, GreyHistogram* grey);

 private:
  int ensembles_ = 0;
  int width_ = 0, height_ = 0;
  uint32_t tiles_x_ = 0;
  size_t pixels_ = 0;  // slots: whole tiles
  std::vector<uint32_t> tile_origin_;  // per tile: the row-major pixel of its top-left corner
  size_t key_bytes_ = 0, filled_bytes_ = 0;
  uint64_t* keys_ = nullptr;
  uint32_t* filled_ = nullptr;
  std::vector<size_t> counts_;
  std::vector<char> prepared_;
};

// Quantized points of a render archive chunk: 8-byte words holding the colour (0x00RRGGBB) in
// the low 24 bits, then x, y, z with bits[0..2] bits each. Decoded exactly as
// ChunkQuantizer::Decode (min + q * step, in double), then rounded to float.
struct QuantizedPoints {
  const uint64_t* words = nullptr;
  uint64_t count = 0;
  uint64_t first_index = 0;  // archive index of words[0]
  double min[3] = {0, 0, 0};
  double step[3] = {0, 0, 0};
  int bits[3] = {0, 0, 0};
  // Points outside it are not drawn (the chunk's frame); null: all are. Each kept point keeps its
  // archive index.
  const ClipRegion* clip = nullptr;
};

// Where a call draws: every point into buffers' ensemble `base` (the archive's ensembles are
// runs of points, render/archive.h EnsembleSlices).
struct EnsembleSelection {
  uint64_t seed = 1;         // of the stochastic rounding of point sizes
  int base = 0;              // < buffers->ensembles()
  double point_size = 1.0;   // as SizedSplat, with the archive index as the point's index
};

// Decodes, projects and z-tests the points in one pass (perspective or orthographic as `p`
// says; the whole image, rows [0, height)) and returns how many were drawn (in view or not; inside
// the clip region).
// The keys equal SplatPoints' / SplatPointsSized's for the same float positions.
uint64_t SplatQuantized(const KernelTransform& t, const KernelProjection& p, const QuantizedPoints& points,
                        const EnsembleSelection& selection, EnsembleBuffers* buffers);

}  // namespace candi::render

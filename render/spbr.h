// Stochastic point-based rendering (SPBR) of a SplatCloud.
//
// Each of the L ensembles is drawn with an ordinary z-buffer (one-pixel points, or larger with
// stochastic rounding); the nearest point's colour of every pixel is added to exact integer sums,
// and the image is (sum + (L - hits) * background) / L: the expected value is front-to-back
// alpha blending with no depth sort (ALGORITHMS.md §1). Ensembles are spread over threads, each
// with its own z-buffer and sums; integer sums make the image identical for any thread count.
// The camera is in the SplatCloud's render frame.
#pragma once

#include <array>
#include <cstdint>

#include "core/image.h"
#include "core/progress.h"
#include "core/spbr_settings.h"
#include "render/camera.h"
#include "render/frame.h"
#include "render/splat_cloud.h"

namespace candi::render {

// How a SplatCloud is drawn; its L, seed and point size are the cloud's (SplatCloudOptions::spbr;
// a splat's side in pixels, above 3 an equal-area disc).
struct SpbrOptions {
  int ensembles = 0;          // > 0: only the first k ensembles (progressive preview); 0: all L
  int threads = 0;            // 0: as many as TBB allows; otherwise 1..256
  void Check() const;
};

struct SpbrResult {
  Accumulator sums;         // per pixel R, G, B sums and hits over the rendered ensembles
  int ensembles = 0;        // k: ensembles rendered (the divisor)
  int repeat_level = 0;     // L of the SplatCloud
  uint64_t seed = 0;
  uint64_t copies = 0;      // points splatted (copies)
  // Grey-value histogram of the first ensemble's drawn pixels: an opaque (L = 1) view of a random
  // subset, for the brightness adjustment.
  std::array<uint64_t, 256> first_ensemble_grey{};
  double milliseconds = 0;
};

SpbrResult RenderSpbr(const SpbrOptions& options, const Camera& camera, const SplatCloud& cloud,
                      const ProgressCallback& progress = nullptr);

// Brightness (Uchida et al.): T = the grey level above which the brightest 1 % of the first
// ensemble's pixels lie; the gain is the smallest multiple of 0.01, >= 1, that lifts 1 % of the
// image's covered pixels (hits > 0) to T. The gain multiplies the points' part of the average
// only (not the background), before quantization.
double AutoBrightnessGain(const SpbrResult& result);

// The gain `brightness` gives `result`: its fixed gain, or the automatic one (which needs more
// than one ensemble: 1 for a single ensemble). candi render's, the viewer's and a section's rule.
double BrightnessGain(const Brightness& brightness, const SpbrResult& result);

// Average colour per pixel as floats in [0, 255]:
// (gain * sum + (k - hits) * background) / k, clamped.
ImageF AverageImage(const SpbrResult& result, Rgb8 background, double gain = 1.0);
Image8 ToImage8(const ImageF& average);    // rounded
Image16 ToImage16(const ImageF& average);  // value * 257, rounded

}  // namespace candi::render

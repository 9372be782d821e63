// Depth-map accuracy as in the paper's Table 2 (the Eigen et al. / BTS set), in one convention.
//
// Convention: prediction and ground truth are depth levels (relief_image.h: 0..255 from the
// panel's front plane, 255 = the wall). A pixel counts when the ground truth is finite and
// >= kMinValidLevel (zero depths are "no data", masked as in the paper) and, if a mask is given,
// the mask is non-zero. The prediction is clamped to [kMinValidLevel, kMaxLevel]; a non-finite
// prediction counts as kMinValidLevel (never skipped, so NaN cannot flatter a model).
// RMSE is in levels (x depth_m / 255 for metres); logs are natural.
#pragma once

#include <cstdint>
#include <string>

#include "core/image.h"

namespace candi::relief {

struct DepthMetrics {
  double delta1 = 0, delta2 = 0, delta3 = 0;  // fraction with max(p/g, g/p) < 1.25, 1.25^2, 1.25^3
  double rmse = 0;      // sqrt(mean (p - g)^2), levels
  double rmse_log = 0;  // sqrt(mean (ln p - ln g)^2)
  double abs_rel = 0;   // mean |p - g| / g
  double sq_rel = 0;    // mean (p - g)^2 / g
  int64_t count = 0;    // valid pixels; all metrics are 0 when count is 0
};

// Sums over many images (panels), so that every valid pixel weighs the same.
class DepthMetricsAccumulator {
 public:
  // prediction, ground truth: same size, one channel; mask: empty or same size.
  void Add(const ImageF& prediction, const ImageF& ground_truth, const Image8& mask = Image8());
  DepthMetrics Result() const;

 private:
  double d1_ = 0, d2_ = 0, d3_ = 0, se_ = 0, sle_ = 0, ar_ = 0, sr_ = 0;
  int64_t n_ = 0;
};

DepthMetrics ComputeDepthMetrics(const ImageF& prediction, const ImageF& ground_truth,
                                 const Image8& mask = Image8());

}  // namespace candi::relief

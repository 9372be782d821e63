// Depth-map accuracy as in the paper's Table 2 (the Eigen et al. / BTS set), in one convention.
//
// Convention: prediction and ground truth are depth levels (relief_image.h: 0..255 from the
// panel's front plane, 255 = the wall). A pixel counts when the ground truth is finite and
// >= kMinValidLevel (zero depths are "no data", masked as in the paper) and, if a mask is given,
// the mask is non-zero. The prediction is clamped to [kMinValidLevel, kMaxLevel]; a non-finite
// prediction counts as kMinValidLevel (never skipped, so NaN cannot flatter a model).
// RMSE is in levels (x depth_m / 255 for metres); logs are natural.
//
// Surface metrics (SurfaceMetricsAccumulator) score shape rather than absolute depth, in the same
// convention (validity from the ground truth and mask, the prediction clamped, NaN = front):
//  - normals: at a pixel whose ground truth is valid there and normal_step pixels away in the four
//    axis directions, the normals of both maps as height fields (x, y in pixels, z = level *
//    level_per_pixel) from central differences over those pixels, n = normalize(-dz/dx, -dz/dy,
//    1); the error is the angle between them in degrees. Pixels within normal_step of the border
//    and images narrower or lower than 2 normal_step + 1 pixels score nothing. The median comes from
//    a 0.01-degree histogram (bounded memory over any number of images), so it is exact to
//    0.01 degree; mean and the within-threshold fractions are exact.
//  - depth edges: pixel p is an edge of a map when p and a 4-neighbour q are both valid (by the
//    ground truth for both maps, so a prediction is only judged where the truth is known) and
//    level(q) - level(p) > edge_jump_levels, i.e. p is the near, occluding side. A predicted edge
//    is correct when a true edge lies within edge_tolerance_px (Euclidean, integer offsets), and
//    vice versa for recall; matched and total counts are summed over images.
// A rate whose count is 0 (precision with no predicted edges, recall with no true edges, every
// normal metric with count 0) is undefined and reported as 0: read the counts alongside.
// Not thread-safe: one accumulator per thread.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

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

struct SurfaceMetricOptions {
  // Size of one depth level in pixel widths: (depth_m / 255) / (metres per pixel); (0, 1e6].
  double level_per_pixel = 1.0;
  // Normals from differences between the pixels this far on either side, [1, 16]: more than 1
  // where the ground truth is noisy at the pixel scale (a dense cloud), so that the metric reads
  // the surface, not the noise.
  int normal_step = 1;
  // A depth discontinuity: a 4-neighbour farther by more than this, levels; finite, > 0.
  double edge_jump_levels = 10;
  // An edge matches one within this Euclidean distance, pixels; [0, 16].
  int edge_tolerance_px = 2;
  // Throws std::invalid_argument naming the field, its value and the rule (NaN is rejected).
  void Check() const;
};

struct NormalMetrics {
  double mean_deg = 0, median_deg = 0;                 // angle between predicted and true normal
  double within_11 = 0, within_22 = 0, within_30 = 0;  // fraction < 11.25, 22.5, 30 degrees
  int64_t count = 0;                                   // pixels scored; all 0 when count is 0
};

struct EdgeMetrics {
  double precision = 0, recall = 0, f1 = 0;  // within the tolerance; 0 = undefined when count is 0
  int64_t predicted = 0, truth = 0;          // edge pixels in the prediction / the ground truth
};

// Sums over many images like DepthMetricsAccumulator, so every scored pixel weighs the same.
class SurfaceMetricsAccumulator {
 public:
  // Throws std::invalid_argument on invalid options.
  explicit SurfaceMetricsAccumulator(const SurfaceMetricOptions& options = {});
  // prediction, ground truth: same size, one channel; mask: empty or same size.
  void Add(const ImageF& prediction, const ImageF& ground_truth, const Image8& mask = Image8());
  NormalMetrics Normals() const;
  EdgeMetrics Edges() const;

 private:
  SurfaceMetricOptions options_;
  std::vector<int64_t> histogram_;  // normal angles in 0.01-degree bins over [0, 180]
  double angle_sum_ = 0, min_angle_ = 180, max_angle_ = 0;
  int64_t within_11_ = 0, within_22_ = 0, within_30_ = 0, normals_ = 0;
  int64_t predicted_ = 0, predicted_matched_ = 0, truth_ = 0, truth_matched_ = 0;
};

}  // namespace candi::relief

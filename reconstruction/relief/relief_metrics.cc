#include "reconstruction/relief/relief_metrics.h"

#include <algorithm>
#include <cmath>

#include "core/check.h"
#include "reconstruction/relief/relief_image.h"

namespace candi::relief {

void DepthMetricsAccumulator::Add(const ImageF& prediction, const ImageF& ground_truth,
                                  const Image8& mask) {
  CANDI_CHECK(prediction.width() == ground_truth.width() &&
              prediction.height() == ground_truth.height())
      << "prediction " << prediction.width() << "x" << prediction.height() << ", ground truth "
      << ground_truth.width() << "x" << ground_truth.height();
  CANDI_CHECK(prediction.channels() == 1 && ground_truth.channels() == 1);
  CANDI_CHECK(mask.empty() || mask.values().size() == ground_truth.values().size());
  for (size_t i = 0; i < ground_truth.values().size(); ++i) {
    const double g = ground_truth.values()[i];
    if (!std::isfinite(g) || g < kMinValidLevel || (!mask.empty() && mask.values()[i] == 0)) continue;
    double p = prediction.values()[i];
    p = std::isfinite(p) ? std::clamp(p, kMinValidLevel, kMaxLevel) : kMinValidLevel;
    const double ratio = std::max(p / g, g / p), e = p - g, le = std::log(p) - std::log(g);
    d1_ += ratio < 1.25;
    d2_ += ratio < 1.25 * 1.25;
    d3_ += ratio < 1.25 * 1.25 * 1.25;
    se_ += e * e;
    sle_ += le * le;
    ar_ += std::abs(e) / g;
    sr_ += e * e / g;
    ++n_;
  }
}

DepthMetrics DepthMetricsAccumulator::Result() const {
  DepthMetrics m;
  m.count = n_;
  if (n_ == 0) return m;
  const double n = static_cast<double>(n_);
  m.delta1 = d1_ / n;
  m.delta2 = d2_ / n;
  m.delta3 = d3_ / n;
  m.rmse = std::sqrt(se_ / n);
  m.rmse_log = std::sqrt(sle_ / n);
  m.abs_rel = ar_ / n;
  m.sq_rel = sr_ / n;
  return m;
}

DepthMetrics ComputeDepthMetrics(const ImageF& prediction, const ImageF& ground_truth,
                                 const Image8& mask) {
  DepthMetricsAccumulator acc;
  acc.Add(prediction, ground_truth, mask);
  return acc.Result();
}

}  // namespace candi::relief

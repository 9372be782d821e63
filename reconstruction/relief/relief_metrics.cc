#include "reconstruction/relief/relief_metrics.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "core/check.h"
#include "reconstruction/relief/relief_image.h"

namespace candi::relief {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kBinDeg = 0.01;  // normal-angle histogram resolution: 18000 bins over [0, 180]
constexpr int kBins = 18000;

// One Add() call's maps as doubles: the prediction clamped (NaN = front, as in
// DepthMetricsAccumulator) and the ground-truth validity, which also decides where the
// prediction is judged.
struct Field {
  int w = 0, h = 0;
  std::vector<double> truth, prediction;
  std::vector<uint8_t> valid;
};

Field Prepare(const ImageF& prediction, const ImageF& ground_truth, const Image8& mask) {
  CANDI_CHECK(prediction.width() == ground_truth.width() &&
              prediction.height() == ground_truth.height())
      << "prediction " << prediction.width() << "x" << prediction.height() << ", ground truth "
      << ground_truth.width() << "x" << ground_truth.height();
  CANDI_CHECK(prediction.channels() == 1 && ground_truth.channels() == 1);
  CANDI_CHECK(mask.empty() || mask.values().size() == ground_truth.values().size());
  Field f;
  f.w = ground_truth.width();
  f.h = ground_truth.height();
  const size_t n = ground_truth.values().size();
  f.truth.assign(n, 0.0);
  f.prediction.assign(n, kMinValidLevel);
  f.valid.assign(n, 0);
  for (size_t i = 0; i < n; ++i) {
    const double g = ground_truth.values()[i], p = prediction.values()[i];
    f.valid[i] = std::isfinite(g) && g >= kMinValidLevel && (mask.empty() || mask.values()[i] != 0);
    if (f.valid[i]) f.truth[i] = g;  // invalid truth stays 0 so no NaN reaches the arithmetic
    if (std::isfinite(p)) f.prediction[i] = std::clamp(p, kMinValidLevel, kMaxLevel);
  }
  return f;
}

// Angles (degrees) between the height-field normals of prediction and truth at every pixel whose
// central differences read only valid truth.
std::vector<double> NormalAngles(const Field& f, double level_per_pixel, int step) {
  std::vector<double> angles;
  const double s = level_per_pixel / (2.0 * step);  // the central difference spans 2 step pixels
  const size_t dy = static_cast<size_t>(step) * f.w;
  for (int y = step; y + step < f.h; ++y) {
    for (int x = step; x + step < f.w; ++x) {
      const size_t i = static_cast<size_t>(y) * f.w + x, left = i - step, right = i + step;
      const size_t up = i - dy, down = i + dy;
      if (!(f.valid[i] && f.valid[left] && f.valid[right] && f.valid[up] && f.valid[down])) {
        continue;
      }
      const auto normal = [&](const std::vector<double>& z) {
        return Eigen::Vector3d(-s * (z[right] - z[left]), -s * (z[down] - z[up]), 1.0);
      };
      const Eigen::Vector3d a = normal(f.prediction), b = normal(f.truth);
      // atan2(|a x b|, a . b) equals acos of the normalised dot product but keeps its precision
      // near 0, where acos has infinite slope (a 1-ulp dot error would read as ~1e-6 degree).
      angles.push_back(std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / kPi);
    }
  }
  return angles;
}

// 1 where the pixel is valid and is the near side of a jump larger than `jump` levels to a valid
// 4-neighbour.
std::vector<uint8_t> EdgeMask(const Field& f, const std::vector<double>& z, double jump) {
  std::vector<uint8_t> edge(z.size(), 0);
  for (int y = 0; y < f.h; ++y) {
    for (int x = 0; x < f.w; ++x) {
      const size_t i = static_cast<size_t>(y) * f.w + x;
      if (!f.valid[i]) continue;
      const auto farther = [&](size_t j) { return f.valid[j] && z[j] - z[i] > jump; };
      edge[i] = (x > 0 && farther(i - 1)) || (x + 1 < f.w && farther(i + 1)) ||
                (y > 0 && farther(i - f.w)) || (y + 1 < f.h && farther(i + f.w));
    }
  }
  return edge;
}

// Integer offsets within `radius` (Euclidean), nearest first so a typical match exits early.
std::vector<std::pair<int, int>> DiskOffsets(int radius) {
  std::vector<std::pair<int, int>> offsets;
  for (int dy = -radius; dy <= radius; ++dy) {
    for (int dx = -radius; dx <= radius; ++dx) {
      if (dx * dx + dy * dy <= radius * radius) offsets.emplace_back(dx, dy);
    }
  }
  std::stable_sort(offsets.begin(), offsets.end(), [](const auto& a, const auto& b) {
    return a.first * a.first + a.second * a.second < b.first * b.first + b.second * b.second;
  });
  return offsets;
}

bool AnyWithin(const std::vector<uint8_t>& mask, int w, int h, int x, int y,
               const std::vector<std::pair<int, int>>& offsets) {
  for (const auto& [dx, dy] : offsets) {
    const int u = x + dx, v = y + dy;
    if (u >= 0 && u < w && v >= 0 && v < h && mask[static_cast<size_t>(v) * w + u]) return true;
  }
  return false;
}

struct Matched {
  int64_t total = 0, matched = 0;  // edge pixels of `from`; those with an edge of `to` near
};

Matched MatchEdges(const std::vector<uint8_t>& from, const std::vector<uint8_t>& to, int w, int h,
                   const std::vector<std::pair<int, int>>& offsets) {
  Matched m;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!from[static_cast<size_t>(y) * w + x]) continue;
      ++m.total;
      m.matched += AnyWithin(to, w, h, x, y, offsets);
    }
  }
  return m;
}

// The bin holding the rank-th smallest angle (0-based).
int BinOfRank(const std::vector<int64_t>& histogram, int64_t rank) {
  int64_t seen = 0;
  for (int b = 0; b < static_cast<int>(histogram.size()); ++b) {
    seen += histogram[b];
    if (seen > rank) return b;
  }
  return static_cast<int>(histogram.size()) - 1;
}

}  // namespace

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

void SurfaceMetricOptions::Check() const {
  // The upper bound keeps the cross products of normals far from overflow.
  CANDI_CHECK_OPTION(level_per_pixel > 0 && level_per_pixel <= 1e6, level_per_pixel, "in (0, 1e6]");
  CANDI_CHECK_OPTION(edge_jump_levels > 0 && std::isfinite(edge_jump_levels), edge_jump_levels,
                     "a finite number > 0");
  CANDI_CHECK_OPTION_IN(normal_step, 1, 16);
  CANDI_CHECK_OPTION_IN(edge_tolerance_px, 0, 16);
}

SurfaceMetricsAccumulator::SurfaceMetricsAccumulator(const SurfaceMetricOptions& options)
    : options_(options), histogram_(kBins, 0) {
  options_.Check();
}

void SurfaceMetricsAccumulator::Add(const ImageF& prediction, const ImageF& ground_truth,
                                    const Image8& mask) {
  const Field f = Prepare(prediction, ground_truth, mask);
  for (const double a : NormalAngles(f, options_.level_per_pixel, options_.normal_step)) {
    angle_sum_ += a;
    min_angle_ = std::min(min_angle_, a);
    max_angle_ = std::max(max_angle_, a);
    within_11_ += a < 11.25;
    within_22_ += a < 22.5;
    within_30_ += a < 30;
    ++histogram_[std::min(static_cast<int>(a / kBinDeg), kBins - 1)];
    ++normals_;
  }
  const std::vector<uint8_t> truth = EdgeMask(f, f.truth, options_.edge_jump_levels),
                             predicted = EdgeMask(f, f.prediction, options_.edge_jump_levels);
  const auto offsets = DiskOffsets(options_.edge_tolerance_px);
  const Matched p = MatchEdges(predicted, truth, f.w, f.h, offsets);
  const Matched t = MatchEdges(truth, predicted, f.w, f.h, offsets);
  predicted_ += p.total;
  predicted_matched_ += p.matched;
  truth_ += t.total;
  truth_matched_ += t.matched;
}

NormalMetrics SurfaceMetricsAccumulator::Normals() const {
  NormalMetrics m;
  m.count = normals_;
  if (normals_ == 0) return m;
  const double n = static_cast<double>(normals_);
  m.mean_deg = angle_sum_ / n;
  m.within_11 = within_11_ / n;
  m.within_22 = within_22_ / n;
  m.within_30 = within_30_ / n;
  // Bin centres of the two middle ranks, clamped to the observed range: exact when all angles
  // agree (e.g. a perfect prediction reads 0, not half a bin).
  const auto centre = [](int b) { return (b + 0.5) * kBinDeg; };
  const double median = 0.5 * (centre(BinOfRank(histogram_, (normals_ - 1) / 2)) +
                               centre(BinOfRank(histogram_, normals_ / 2)));
  m.median_deg = std::clamp(median, min_angle_, max_angle_);
  return m;
}

EdgeMetrics SurfaceMetricsAccumulator::Edges() const {
  EdgeMetrics m;
  m.predicted = predicted_;
  m.truth = truth_;
  if (predicted_ > 0) m.precision = static_cast<double>(predicted_matched_) / predicted_;
  if (truth_ > 0) m.recall = static_cast<double>(truth_matched_) / truth_;
  if (m.precision + m.recall > 0) m.f1 = 2 * m.precision * m.recall / (m.precision + m.recall);
  return m;
}

}  // namespace candi::relief

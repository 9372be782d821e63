// Stage 1 of the section lines (section_lines_internal.h): the typical gap between the points
// along a curve, which sets the automatic spacing, and the noise across the curves, which sets
// the fits' least scale.
#include "section/section_lines_internal.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <nanoflann.hpp>
#include <utility>
#include <vector>

#include "core/kd_tree_adaptor.h"
#include "core/rng.h"

namespace candi::section::lines_internal {

namespace {

// Automatic spacing: k-th neighbour over a sample of the points.
constexpr int kDensityNeighbours = 2;  // few: the k-th is still on the same curve near another
constexpr size_t kDensitySample = size_t{1} << 18;
constexpr size_t kDensityQueries = 2048;
constexpr uint64_t kSampleStream = 0x73656374696f6eULL;  // "section"

using SampleCloud = KdTreeAdaptor<Eigen::Vector2d>;
using SampleTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, SampleCloud>,
                                        SampleCloud, 2, uint32_t>;

uint64_t CoordinateHash(const Eigen::Vector2d& p) {
  uint64_t u, v;
  const double x = p.x() + 0.0, y = p.y() + 0.0;  // -0 -> +0
  std::memcpy(&u, &x, sizeof u);
  std::memcpy(&v, &y, sizeof v);
  return Mix64(u ^ Mix64(v ^ kSampleStream));
}

// A sample of the points chosen by a hash of their coordinates (so independent of their order),
// sorted by that hash.
SampleCloud SamplePoints(const std::vector<Eigen::Vector2d>& input, const Eigen::Vector2d& origin,
                         size_t finite) {
  const double fraction = std::min(1.0, static_cast<double>(kDensitySample) / finite);
  std::vector<std::pair<uint64_t, Eigen::Vector2d>> picked;
  for (const Eigen::Vector2d& p : input) {
    if (!p.allFinite()) continue;
    const uint64_t h = CoordinateHash(p);
    if (fraction == 1.0 || ToUnit(h) < fraction) picked.emplace_back(h, p - origin);
  }
  std::sort(picked.begin(), picked.end(), [](const auto& a, const auto& b) {
    if (a.first != b.first) return a.first < b.first;
    return a.second.x() != b.second.x() ? a.second.x() < b.second.x() : a.second.y() < b.second.y();
  });
  SampleCloud sample;
  for (const auto& entry : picked) sample.points.push_back(entry.second);
  return sample;
}

}  // namespace

// The typical gap between consecutive points along a curve, m (0 if unknown). k neighbours of a
// point on a curve span about 2 r_k of it; for Poisson sampling at lambda points/m the median of
// r_k is about (k - 1/3) / (2 lambda). A sample of a fraction f of the points has gaps 1/f times
// longer.
double TypicalPointGap(const std::vector<Eigen::Vector2d>& input, const Eigen::Vector2d& origin,
                       size_t finite) {
  const SampleCloud sample = SamplePoints(input, origin, finite);
  const size_t n = sample.points.size();
  if (n < 2) return 0.0;
  const size_t k = std::min<size_t>(kDensityNeighbours, n - 1);
  SampleTree tree(2, sample, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  std::vector<uint32_t> found(k + 1);
  std::vector<double> dist_sq(k + 1), radii;
  for (size_t q = 0; q < std::min(n, kDensityQueries); ++q) {
    const size_t got = tree.knnSearch(sample.points[q].data(), k + 1, found.data(), dist_sq.data());
    if (got == k + 1 && dist_sq[k] > 0) radii.push_back(std::sqrt(dist_sq[k]));
  }
  if (radii.empty()) return 0.0;
  std::nth_element(radii.begin(), radii.begin() + radii.size() / 2, radii.end());
  const double r = radii[radii.size() / 2];
  const double fraction = static_cast<double>(n) / static_cast<double>(finite);
  return 2.0 * r / (static_cast<double>(k) - 1.0 / 3.0) * fraction;
}

// The noise: the median inlier scale of adaptive fits at up to 256 points spread over the grid.
// The fits' least scale becomes 3 x the noise if that is more than tau_floor.
void AdaptToNoise(Context* ctx) {
  constexpr size_t kSamples = 256;
  const std::vector<Eigen::Vector2d>& points = ctx->grid.points;
  const size_t stride = std::max<size_t>(1, points.size() / kSamples);
  std::vector<double> scales;
  Window win;
  for (size_t k = 0; k < points.size(); k += stride) {
    Gather(ctx->grid, points[k], ctx->scales.radius, &win);
    const CurveFit fit = FitCurve(&win, Eigen::Vector2d::Zero(), ctx->scales);
    if (fit.ok && fit.support >= kMinSupport) scales.push_back(fit.scale);
  }
  ctx->scales.adaptive = false;
  if (scales.empty()) return;
  std::nth_element(scales.begin(), scales.begin() + scales.size() / 2, scales.end());
  ctx->noise = scales[scales.size() / 2];
  ctx->scales.tau_floor = std::max(ctx->scales.tau_floor, 3 * ctx->noise);
  ctx->scales.tau_start = std::max(ctx->scales.tau_start, ctx->scales.tau_floor);
}

}  // namespace candi::section::lines_internal

#include "reconstruction/photogrammetry/registration/cleaning.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>

#include "core/check.h"
#include "core/text_format.h"
#include "reconstruction/photogrammetry/registration/local_points.h"

namespace candi::photogrammetry {

namespace {

// One occupied cell's candidate: its cell, its squared distance to the cell centre, its index.
struct VoxelEntry {
  std::array<int64_t, 3> cell;
  double centre_sq;
  size_t index;
  bool operator<(const VoxelEntry& o) const {
    if (cell != o.cell) return cell < o.cell;
    if (centre_sq != o.centre_sq) return centre_sq < o.centre_sq;
    return index < o.index;
  }
};

// Cell index limit: keeps floor(w / leaf) exactly representable and far from int64 overflow.
constexpr double kMaxCell = 4.611686018427387904e18;  // 2^62

VoxelEntry MakeEntry(const Eigen::Vector3d& world, double leaf, size_t index) {
  VoxelEntry e;
  e.centre_sq = 0;
  for (int k = 0; k < 3; ++k) {
    const double c = std::floor(world[k] / leaf);
    if (!(std::abs(c) < kMaxCell)) {
      throw std::invalid_argument("voxel leaf " + FormatDouble(leaf) + " m is too small for " +
                                  "coordinate " + FormatDouble(world[k]) +
                                  " m: more than 2^62 cells from the origin");
    }
    e.cell[k] = static_cast<int64_t>(c);
    const double d = world[k] - (c + 0.5) * leaf;
    e.centre_sq += d * d;
  }
  e.index = index;
  return e;
}

}  // namespace

void CleanOptions::Check() const {
  CANDI_CHECK_OPTION_IN(sor_neighbours, 1, 10000);
  CANDI_CHECK_OPTION(std::isfinite(sor_std_multiplier) && sor_std_multiplier > 0,
                     sor_std_multiplier, "finite and > 0");
  CANDI_CHECK_OPTION(std::isfinite(voxel) && voxel >= 0, voxel, "finite and >= 0");
}

std::vector<size_t> VoxelThinIndices(const PointCloud& cloud, double leaf) {
  CANDI_CHECK(std::isfinite(leaf) && leaf > 0) << "VoxelThinIndices: leaf = " << leaf;
  CheckFinitePositions(cloud, "voxel thinning");
  std::vector<VoxelEntry> entries;
  entries.reserve(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    entries.push_back(MakeEntry(cloud.WorldPosition(i), leaf, i));
  }
  std::sort(entries.begin(), entries.end());
  std::vector<size_t> kept;
  for (size_t i = 0; i < entries.size(); ++i) {
    if (i == 0 || entries[i].cell != entries[i - 1].cell) kept.push_back(entries[i].index);
  }
  std::sort(kept.begin(), kept.end());
  return kept;
}

PointCloud SelectPoints(const PointCloud& cloud, const std::vector<size_t>& indices) {
  PointCloud out;
  out.SetSchema(cloud.schema);
  out.frame = cloud.frame;
  out.meta = cloud.meta;
  out.Reserve(indices.size());
  for (size_t i : indices) {
    CANDI_CHECK_LT(i, cloud.size());
    out.AppendFrom(cloud, i);
  }
  return out;
}

CleanResult CleanPointCloud(const CleanOptions& options, const PointCloud& cloud,
                            const ProgressCallback& progress) {
  options.Check();
  cloud.CheckConsistent();
  CleanSummary s;
  s.input = cloud.size();
  std::vector<size_t> kept;
  kept.reserve(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    if (cloud.positions[i].allFinite()) kept.push_back(i);
  }
  s.non_finite = s.input - kept.size();
  PointCloud current = kept.size() == cloud.size() ? cloud : SelectPoints(cloud, kept);
  if (progress) progress(1, 3);
  if (options.sor) {
    const std::vector<size_t> inliers =
        StatisticalInliers(current, options.sor_neighbours, options.sor_std_multiplier);
    s.outliers = current.size() - inliers.size();
    if (s.outliers > 0) current = SelectPoints(current, inliers);
  }
  if (progress) progress(2, 3);
  if (options.voxel > 0) {
    const std::vector<size_t> thin = VoxelThinIndices(current, options.voxel);
    s.thinned = current.size() - thin.size();
    if (s.thinned > 0) current = SelectPoints(current, thin);
  }
  if (progress) progress(3, 3);
  s.output = current.size();
  return {std::move(current), s};
}

}  // namespace candi::photogrammetry

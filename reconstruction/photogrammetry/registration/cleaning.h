// Cleaning a point cloud: statistical outlier removal (PCL) and voxel thinning (own, exact).
//
// CleanPointCloud runs, in this order: removal of points whose position is not finite, statistical
// outlier removal (pcl::StatisticalOutlierRemoval: a point goes when the mean distance to its k
// nearest neighbours exceeds the mean of that figure over the cloud plus std_multiplier standard
// deviations), then voxel thinning. Every attribute of a kept point (colour, alpha, normal, layer,
// scalar fields) is kept unchanged and the kept points stay in input order; schema, frame and
// metadata are those of the input.
//
// Voxel thinning keeps, in each occupied cubic cell of side `leaf`, the one point nearest the
// cell's centre (ties: the lowest index) — a real point, never an average, so its attributes
// survive. Cells are anchored at the world origin (cell k covers [k leaf, (k+1) leaf) in world
// coordinates), so the result does not depend on the cloud's shift. Cell indices are 64-bit:
// extents of 1e7 m with 1e-9 m leaves are fine (PCL's VoxelGrid overflows its 32-bit index there
// and warns "Leaf size is too small"); coordinates beyond 2^62 leaves throw std::invalid_argument.
//
// Frames: SOR works in float relative to the cloud's rounded bounding-box centre (local_points.h),
// so survey coordinates keep mm detail. Deterministic: the output depends only on the options and
// the input (single-threaded). Cost: SOR O(N k log N) (kd-tree), thinning O(N log N) (a sort).
#pragma once

#include <cstdint>
#include <vector>

#include "core/point_cloud.h"
#include "core/progress.h"

namespace candi::photogrammetry {

struct CleanOptions {
  bool sor = true;                   // run statistical outlier removal
  int sor_neighbours = 16;           // k (PCL's mean-k), [1, 10000]
  double sor_std_multiplier = 3.0;   // threshold in standard deviations, > 0
  double voxel = 0;                  // thinning cell side, m, >= 0; 0 = no thinning
  void Check() const;                // throws std::invalid_argument("CleanOptions::field = ...")
};

struct CleanSummary {
  uint64_t input = 0;       // points read
  uint64_t non_finite = 0;  // removed: position NaN or infinite
  uint64_t outliers = 0;    // removed by statistical outlier removal
  uint64_t thinned = 0;     // removed by voxel thinning
  uint64_t output = 0;      // points kept
};

struct CleanResult {
  PointCloud cloud;
  CleanSummary summary;
};

// `progress` (optional) receives the step number done out of 3.
CleanResult CleanPointCloud(const CleanOptions& options, const PointCloud& cloud,
                            const ProgressCallback& progress = nullptr);

// Indices (ascending) of the points statistical outlier removal keeps; positions must be finite
// (InputError otherwise). Fewer than 2 points: all kept.
std::vector<size_t> StatisticalInliers(const PointCloud& cloud, int neighbours,
                                       double std_multiplier);

// Indices (ascending) of the points voxel thinning keeps; leaf > 0; positions must be finite
// (InputError otherwise).
std::vector<size_t> VoxelThinIndices(const PointCloud& cloud, double leaf);

// The points `indices` (each < size) of `cloud`, with every attribute, in that order.
PointCloud SelectPoints(const PointCloud& cloud, const std::vector<size_t>& indices);

}  // namespace candi::photogrammetry

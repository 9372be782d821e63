// Per-point surface density (points per square metre) of a point cloud sampled from surfaces.
//
// Two estimators, both counting the *other* points near each point (the point itself excluded):
//  - kKdTree: neighbours within a sphere of radius r (nanoflann kd-tree). A locally planar surface
//    cut by the sphere is a disc of area pi r^2 whatever its orientation, so
//        density_i = (count_i - 1) / (pi r^2).
//    For points sampled uniformly (Poisson) at density rho, the expected number of *other*
//    points in the disc around a point is exactly rho pi r^2 (Slivnyak), so the mean is
//    unbiased; counting the point itself would add 1/k (3 % at k = 32).
//  - kVoxel: counts per cubic cell of side h = sqrt(pi) r (face area = the disc's area):
//        density_i = (count_cell - 1) / A_cell,
//    A_cell = the area of the cell's section by the plane fitted to the cell's points (PCA
//    through their mean; sampling/plane_in_cube.h), h^2 when they define none (< 3 points,
//    collinear). Plain count / h^2 is right only for axis-aligned surfaces: 7 % low on average
//    for tilted ones, and from 29 % low to 41 % high on a wall at 45° to the grid, depending
//    on where the wall lies. Cheaper than kKdTree: one sort instead of a search per point;
//    coarser: all points of a cell share one value.
// Automatic radius (radius = 0): r = the median, over a seeded sample of up to `sample_size`
// points, of the distance to the target_neighbours-th nearest other point, so the median point
// has about target_neighbours neighbours. Degenerate clouds: when that median is 0 (over half
// the sampled points have target_neighbours coincident copies), r = sqrt(k A / (pi N)) with A
// the product of the bounding box's two largest extents; if that is 0 too (points on one line
// or one spot), r = half the largest extent, else 1 m. Coincident points then get a finite
// density; a single point gets 0.
//
// Weights: with `weight_field` set, each point counts as that many points (e.g. an SPBR
// multiplicity): count_i becomes the sum of the weights in the sphere or cell, and the point
// itself removes min(w_i, 1). Weights must be finite and >= 0 (InputError otherwise).
//
// Frame: positions are read in the cloud's local frame and converted to float relative to the
// bounding-box centre (kd-tree) or to double offsets from the box minimum (voxel), so a cloud
// far from its origin (1e6 m) gives the same densities as the same cloud near it.
// Determinism: results depend on the options and the cloud only, never on the thread count.
// Failure: NaN or infinite positions are a caller error (the readers never produce them):
// CANDI_CHECK (InternalError). Cost: kd-tree O(N log N + N k), voxel O(N log N) (a sort); the
// automatic radius builds the kd-tree for kVoxel too (over half its time at 10^6 points): pass a
// radius to skip it. The voxel grid holds at most 2^21 cells per axis (std::invalid_argument).
// Thread-safe (reentrant); `threads` limits the TBB workers used.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "core/progress.h"

namespace candi::sampling {

enum class DensityMethod { kKdTree, kVoxel };

// "kdtree" / "voxel"; the parser throws std::invalid_argument naming the text.
std::string DensityMethodName(DensityMethod method);
DensityMethod ParseDensityMethod(const std::string& name);

struct DensityOptions {
  DensityMethod method = DensityMethod::kKdTree;
  double radius = 0.0;         // support radius r, m; >= 0; 0 = automatic (see above)
  int target_neighbours = 32;  // neighbours of the median point for the automatic radius, >= 1
  int sample_size = 1024;      // points sampled for the automatic radius, >= 1
  uint64_t seed = 1;           // seeds the sample
  int threads = 0;             // worker threads, >= 0; 0 = all available (TBB's default)
  std::string weight_field;    // scalar field counted as a weight per point; "" = weight 1
  ProgressCallback progress;   // called with (points done, total) from worker threads; may be empty
  // Throws std::invalid_argument("DensityOptions::field = value; must be ...").
  void Check() const;
};

struct DensityResult {
  std::vector<double> density;  // points per m^2, one per input point, input order
  DensityMethod method = DensityMethod::kKdTree;
  double radius = 0.0;     // support radius r used, m (kVoxel: h / sqrt(pi))
  double cell_size = 0.0;  // kVoxel: cell side h, m; kKdTree: 0
  double area = 0.0;       // the area the counts refer to, pi r^2 (= h^2), m^2
  bool automatic_radius = false;
  double median_density = 0.0;  // over the points; 0 for an empty cloud
};

// Empty cloud: empty result (radius 0). See the file comment for the estimators and failures.
DensityResult EstimateSurfaceDensity(const DensityOptions& options, const PointCloud& cloud);

}  // namespace candi::sampling

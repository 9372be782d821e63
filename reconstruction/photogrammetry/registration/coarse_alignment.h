// Coarse alignment of two clouds without a start pose: FPFH features (Rusu et al., "Fast Point
// Feature Histograms for 3D registration", ICRA 2009) matched by RANSAC with prerejection
// (pcl::SampleConsensusPrerejective; Buch et al., "Pose estimation using local structure-specific
// shape and appearance context", ICRA 2013). The result is a start for ICP or RegisterScans
// (multi_registration.h), good to a few voxels, not a registration.
//
// Frames: both clouds in world coordinates (their frames' ToWorld); they are re-expressed relative
// to one integer origin (the fixed cloud's, local_points.h) before PCL sees them as float; the
// transform returned is in world coordinates: x_fixed = fixed_from_moving * x_moving.
// Determinism: single-threaded; PCL draws its samples with std::rand, which this function seeds
// with `seed` (std::srand) before the search: same input and seed, same result. It therefore
// touches the process's std::rand state and must not run concurrently with other std::rand users.
// Failure: bad options throw std::invalid_argument; an empty cloud or a non-finite position throws
// InputError; no consensus found is a result (found = false, message), not an exception.
#pragma once

#include <cstdint>
#include <string>

#include "core/point_cloud.h"
#include "core/transform.h"

namespace candi::photogrammetry {

struct CoarseAlignmentOptions {
  double voxel = 0.3;           // m, > 0: both clouds thinned to this for the features
  int normal_neighbours = 16;   // k for the normals, [3, 1000]
  double feature_radius = 1.5;  // m, > voxel: the FPFH support radius
  int max_iterations = 50000;   // RANSAC iterations, [1, 10000000]
  int correspondence_randomness =
      3;  // each sample picks among this many nearest features, [1, 100]
  double similarity_threshold = 0.9;  // prerejection: edge length ratio to keep a sample, (0, 1)
  double inlier_distance = 0.5;       // m, > 0: a moved moving point within this is an inlier
  // [0, 1]: share of inliers to accept a pose. Not lower than the share a wrong pose can reach
  // by laying a dominant plane on itself (a floor on the floor: 0.36 in the courtyard test);
  // lower it only for scans that share less than half their points.
  double min_inlier_fraction = 0.5;
  uint64_t seed = 1;   // std::srand seed for PCL's sampling
  void Check() const;  // throws std::invalid_argument("CoarseAlignmentOptions::field = ...")
};

struct CoarseAlignmentResult {
  bool found = false;                            // a pose with at least min_inlier_fraction inliers
  Rigid3 fixed_from_moving;                      // world coordinates; identity when not found
  double inlier_fraction = 0;                    // [0, 1], of the thinned moving points
  uint64_t moving_points = 0, fixed_points = 0;  // after thinning (with a normal)
  std::string message;                           // one line
};

CoarseAlignmentResult CoarseAlign(const CoarseAlignmentOptions& options, const PointCloud& moving,
                                  const PointCloud& fixed);

}  // namespace candi::photogrammetry

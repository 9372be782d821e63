// Rigid registration: ICP refinement of a moving cloud onto a fixed one (PCL).
//
// Both clouds are re-expressed relative to one common double-precision origin (the fixed cloud's
// rounded bounding-box centre, local_points.h) before PCL sees them as float, so survey
// coordinates (E ~ 4e5, N ~ 9e6 m) keep mm detail; PCL's ICP then runs in double (Scalar =
// double) and the transform is returned in world coordinates (double):
//     x_fixed_world = fixed_from_moving * x_moving_world.
// Methods: point-to-point (pcl::IterativeClosestPoint, SVD) or point-to-plane
// (TransformationEstimationPointToPlaneLLS, linearised), which needs normals on the fixed cloud:
// its own when it has them, else estimated by PCA of k neighbours (point_normals.h); fixed points
// whose normal is undefined are left out of the solve. Voxel thinning (cleaning.h) can reduce
// both clouds for the solve; figures are always measured on the full clouds.
//
// Figures: a moving point "corresponds" when its nearest fixed point lies within
// max_correspondence_distance; overlap = share of moving points that correspond; RMS = root mean
// square of those nearest-point distances (point to point, m). Both are given before (with the
// initial transform) and after.
// Outcomes (a result, never an exception): kConverged; kNotConverged (the iteration limit was
// reached with the transform still changing; the last transform is returned); kNoOverlap (no
// moving point within the distance of the fixed cloud, before or during ICP: the transform
// returned is the initial one). Bad input (an empty cloud, a position NaN or infinite) throws
// InputError; bad options std::invalid_argument. Deterministic, single-threaded, reentrant.
#pragma once

#include <cstdint>
#include <string>

#include "core/point_cloud.h"
#include "core/progress.h"
#include "core/transform.h"

namespace candi::photogrammetry {

enum class IcpMethod { kPointToPoint, kPointToPlane };
std::string IcpMethodName(IcpMethod method);  // "point", "plane"
IcpMethod ParseIcpMethod(const std::string& name);  // throws std::invalid_argument

struct RegistrationOptions {
  double max_correspondence_distance = 0.5;  // m, > 0: pairs farther apart are ignored
  int max_iterations = 50;                   // [1, 100000]
  double translation_epsilon = 1e-5;         // m, >= 0: converged when an iteration moves less
  double rotation_epsilon = 1e-6;            // rad, >= 0: ... and turns less than this
  double relative_mse_epsilon = 1e-7;        // >= 0: or when the MSE changes by less (relative)
  double voxel = 0;                          // m, >= 0: thin both clouds for the solve; 0 = off
  IcpMethod method = IcpMethod::kPointToPlane;
  int normal_neighbours = 16;                // k for estimated normals, [3, 1000]
  Rigid3 initial;                            // initial fixed_from_moving, world coordinates
  void Check() const;  // throws std::invalid_argument("RegistrationOptions::field = ...")
};

enum class RegistrationStatus { kConverged, kNotConverged, kNoOverlap };
std::string RegistrationStatusName(RegistrationStatus status);  // "converged", ...

struct RegistrationResult {
  RegistrationStatus status = RegistrationStatus::kNoOverlap;
  Rigid3 fixed_from_moving;        // world coordinates (the initial transform for kNoOverlap)
  int iterations = 0;              // ICP iterations run
  double rms_before = 0, rms_after = 0;          // m; NaN without correspondences
  double overlap_before = 0, overlap_after = 0;  // [0, 1]
  uint64_t moving_points = 0, fixed_points = 0;  // full clouds
  uint64_t moving_solve_points = 0, fixed_solve_points = 0;  // after thinning (and normals)
  IcpMethod method = IcpMethod::kPointToPlane;   // the method used
  bool normals_estimated = false;  // point-to-plane with normals estimated on the fixed cloud
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // the common local origin, world m
  std::string message;             // one line: what happened (and why it failed)
  bool converged() const { return status == RegistrationStatus::kConverged; }
};

// `progress` (optional) receives iterations done out of max_iterations.
RegistrationResult RegisterPointClouds(const RegistrationOptions& options,
                                       const PointCloud& moving, const PointCloud& fixed,
                                       const ProgressCallback& progress = nullptr);

// `cloud` moved by `transform` (world coordinates), in the cloud's own frame, schema and metadata:
// positions p_local -> R p_local + (R o + t - o) with o the frame's origin (exact to double
// rounding at any shift); normals rotated; every other attribute kept.
PointCloud TransformPointCloud(const Rigid3& transform, const PointCloud& cloud);

}  // namespace candi::photogrammetry

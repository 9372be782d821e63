// ICP with PCL. PCL's registration headers live in this file only (they are slow to compile).
#include "reconstruction/photogrammetry/registration/registration.h"

#include <pcl/point_types.h>
#include <pcl/registration/icp.h>
#include <pcl/registration/transformation_estimation_point_to_plane_lls.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/check.h"
#include "core/text_format.h"
#include "reconstruction/photogrammetry/registration/cleaning.h"
#include "reconstruction/photogrammetry/registration/local_points.h"
#include "reconstruction/photogrammetry/registration/point_index.h"
#include "reconstruction/photogrammetry/registration/point_normals.h"

namespace candi::photogrammetry {

namespace {

using PointT = pcl::PointNormal;
using Cloud = pcl::PointCloud<PointT>;
using Icp = pcl::IterativeClosestPoint<PointT, PointT, double>;
using Criteria = pcl::registration::DefaultConvergenceCriteria<double>;

// Exposes what PCL keeps protected: the iteration count and the last iteration's increment.
class CountingIcp : public Icp {
 public:
  int iterations() const { return nr_iterations_; }
  const Eigen::Matrix4d& last_increment() const { return transformation_; }
};

// World rigid transform -> the same motion in local coordinates x_local = x_world - origin.
Eigen::Matrix4d ToLocal(const Rigid3& world, const Eigen::Vector3d& origin) {
  Eigen::Matrix4d m = world.ToMatrix();
  const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
  m.topRightCorner<3, 1>() = r * origin + world.translation - origin;
  return m;
}

Rigid3 ToWorld(const Eigen::Matrix4d& local, const Eigen::Vector3d& origin) {
  const Eigen::Matrix3d r = local.topLeftCorner<3, 3>();
  const Eigen::Vector3d t = local.topRightCorner<3, 1>() + (origin - r * origin);
  return Rigid3(Eigen::Quaterniond(r), t);
}

std::vector<size_t> SolveIndices(const PointCloud& cloud, double voxel) {
  if (voxel > 0) return VoxelThinIndices(cloud, voxel);
  std::vector<size_t> all(cloud.size());
  for (size_t i = 0; i < all.size(); ++i) all[i] = i;
  return all;
}

// The fixed cloud for the solve: thinned points with normals (own or estimated; points whose
// normal is undefined dropped in point-to-plane mode).
Cloud::Ptr FixedSolveCloud(const RegistrationOptions& o, const PointCloud& fixed,
                           const std::vector<Eigen::Vector3f>& fixed_all,
                           RegistrationResult* r) {
  const std::vector<size_t> idx = SolveIndices(fixed, o.voxel);
  std::vector<Eigen::Vector3f> points, normals;
  points.reserve(idx.size());
  for (size_t i : idx) points.push_back(fixed_all[i]);
  if (o.method == IcpMethod::kPointToPlane) {
    if (fixed.schema.normals) {
      for (size_t i : idx) normals.push_back(fixed.normals[i]);
    } else {
      normals = EstimateNormals(points, o.normal_neighbours);
      r->normals_estimated = true;
    }
  }
  Cloud::Ptr cloud(new Cloud);
  cloud->reserve(points.size());
  for (size_t k = 0; k < points.size(); ++k) {
    PointT p;
    p.getVector3fMap() = points[k];
    if (!normals.empty()) {
      const Eigen::Vector3f& n = normals[k];
      if (!n.allFinite() || n.squaredNorm() < 0.25f) continue;  // no plane here
      p.getNormalVector3fMap() = n.normalized();
    }
    cloud->push_back(p);
  }
  return cloud;
}

Cloud::Ptr MovingSolveCloud(const RegistrationOptions& o, const PointCloud& moving,
                            const std::vector<Eigen::Vector3f>& moving_all) {
  Cloud::Ptr cloud(new Cloud);
  for (size_t i : SolveIndices(moving, o.voxel)) {
    PointT p;
    p.getVector3fMap() = moving_all[i];
    cloud->push_back(p);
  }
  return cloud;
}

bool SmallIncrement(const Eigen::Matrix4d& increment, const RegistrationOptions& o) {
  const Eigen::Matrix3d r = increment.topLeftCorner<3, 3>();
  const double angle = Eigen::AngleAxisd(r).angle();
  return increment.topRightCorner<3, 1>().norm() <= o.translation_epsilon &&
         angle <= o.rotation_epsilon;
}

// Runs ICP from `initial` (local); fills iterations, status and message; returns the local result.
Eigen::Matrix4d RunIcp(const RegistrationOptions& o, Cloud::Ptr moving, Cloud::Ptr fixed,
                       const Eigen::Matrix4d& initial, const ProgressCallback& progress,
                       RegistrationResult* r) {
  CountingIcp icp;
  if (r->method == IcpMethod::kPointToPlane) {
    icp.setTransformationEstimation(std::make_shared<
        pcl::registration::TransformationEstimationPointToPlaneLLS<PointT, PointT, double>>());
  }
  icp.setInputSource(moving);
  icp.setInputTarget(fixed);
  icp.setMaxCorrespondenceDistance(o.max_correspondence_distance);
  icp.setMaximumIterations(o.max_iterations);
  icp.setTransformationEpsilon(o.translation_epsilon * o.translation_epsilon);  // squared, m^2
  icp.setTransformationRotationEpsilon(std::cos(o.rotation_epsilon));           // a cosine
  icp.setEuclideanFitnessEpsilon(o.relative_mse_epsilon);
  std::function<Icp::UpdateVisualizerCallbackSignature> on_iteration;
  int calls = 0;
  if (progress) {
    on_iteration = [&](const Cloud&, const pcl::Indices&, const Cloud&, const pcl::Indices&) {
      progress(static_cast<uint64_t>(calls++), static_cast<uint64_t>(o.max_iterations));
    };
    icp.registerVisualizationCallback(on_iteration);  // calls it once now (0 done)
  }
  Cloud aligned;
  icp.align(aligned, initial);
  r->iterations = icp.iterations();
  const auto state = icp.getConvergeCriteria()->getConvergenceState();
  const std::string after = " after " + std::to_string(r->iterations) + " iteration(s)";
  if (state == Criteria::CONVERGENCE_CRITERIA_NO_CORRESPONDENCES) {
    r->status = RegistrationStatus::kNoOverlap;
    r->message = "no overlap: ICP lost its correspondences (fewer than 3 pairs within " +
                 FormatDouble(o.max_correspondence_distance) + " m)" + after;
    return initial;
  }
  const bool at_limit = state == Criteria::CONVERGENCE_CRITERIA_ITERATIONS ||
                        state == Criteria::CONVERGENCE_CRITERIA_FAILURE_AFTER_MAX_ITERATIONS;
  if (at_limit && !SmallIncrement(icp.last_increment(), o)) {
    r->status = RegistrationStatus::kNotConverged;
    r->message = "not converged: the iteration limit (" + std::to_string(o.max_iterations) +
                 ") was reached with the transform still changing";
  } else {
    r->status = RegistrationStatus::kConverged;
    r->message = "converged" + after;
  }
  return icp.getFinalTransformation();
}

}  // namespace

std::string IcpMethodName(IcpMethod method) {
  return method == IcpMethod::kPointToPoint ? "point" : "plane";
}

IcpMethod ParseIcpMethod(const std::string& name) {
  if (name == "point") return IcpMethod::kPointToPoint;
  if (name == "plane") return IcpMethod::kPointToPlane;
  throw std::invalid_argument("ICP method '" + name + "': must be point or plane");
}

std::string RegistrationStatusName(RegistrationStatus status) {
  switch (status) {
    case RegistrationStatus::kConverged: return "converged";
    case RegistrationStatus::kNotConverged: return "not converged";
    case RegistrationStatus::kNoOverlap: return "no overlap";
  }
  return "?";
}

void RegistrationOptions::Check() const {
  CANDI_CHECK_OPTION(std::isfinite(max_correspondence_distance) && max_correspondence_distance > 0,
                     max_correspondence_distance, "finite and > 0");
  CANDI_CHECK_OPTION_IN(max_iterations, 1, 100000);
  CANDI_CHECK_OPTION(std::isfinite(translation_epsilon) && translation_epsilon >= 0,
                     translation_epsilon, "finite and >= 0");
  CANDI_CHECK_OPTION(rotation_epsilon >= 0 && rotation_epsilon < 1, rotation_epsilon,
                     "in [0, 1) rad");
  CANDI_CHECK_OPTION(std::isfinite(relative_mse_epsilon) && relative_mse_epsilon >= 0,
                     relative_mse_epsilon, "finite and >= 0");
  CANDI_CHECK_OPTION(std::isfinite(voxel) && voxel >= 0, voxel, "finite and >= 0");
  CANDI_CHECK_OPTION_IN(normal_neighbours, 3, 1000);
  CANDI_CHECK_OPTION(initial.translation.allFinite(), initial.translation, "finite");
  CANDI_CHECK_OPTION(initial.rotation.coeffs().allFinite(), initial.rotation.coeffs(), "finite");
}

RegistrationResult RegisterPointClouds(const RegistrationOptions& options,
                                       const PointCloud& moving, const PointCloud& fixed,
                                       const ProgressCallback& progress) {
  options.Check();
  if (moving.empty()) throw InputError("moving cloud", "", "no points to register");
  if (fixed.empty()) throw InputError("fixed cloud", "", "no points to register onto");
  moving.CheckConsistent();
  fixed.CheckConsistent();
  RegistrationResult r;
  r.moving_points = moving.size();
  r.fixed_points = fixed.size();
  r.method = options.method;
  r.fixed_from_moving = options.initial;
  r.origin = CommonOrigin(fixed.WorldBounds());
  const std::vector<Eigen::Vector3f> moving_all = LocalFloatPoints(moving, r.origin, "moving cloud");
  const std::vector<Eigen::Vector3f> fixed_all = LocalFloatPoints(fixed, r.origin, "fixed cloud");
  const Eigen::Matrix4d initial = ToLocal(options.initial, r.origin);
  const double d = options.max_correspondence_distance;
  const PointIndex index(fixed_all);
  const OverlapStats before = MeasureOverlap(index, moving_all, initial, d);
  r.overlap_before = r.overlap_after = before.overlap;
  r.rms_before = r.rms_after = before.rms;
  if (before.correspondences == 0) {
    r.message = "no overlap: no moving point lies within " + FormatDouble(d) +
                " m of the fixed cloud (with the initial transform); give an initial transform "
                "or a larger maximum distance";
    return r;
  }
  Cloud::Ptr fixed_solve = FixedSolveCloud(options, fixed, fixed_all, &r);
  if (r.method == IcpMethod::kPointToPlane && fixed_solve->size() < 3) {
    RegistrationOptions point = options;  // no plane anywhere (a line, a few points)
    point.method = r.method = IcpMethod::kPointToPoint;
    r.normals_estimated = false;
    fixed_solve = FixedSolveCloud(point, fixed, fixed_all, &r);
  }
  Cloud::Ptr moving_solve = MovingSolveCloud(options, moving, moving_all);
  r.moving_solve_points = moving_solve->size();
  r.fixed_solve_points = fixed_solve->size();
  const Eigen::Matrix4d local = RunIcp(options, moving_solve, fixed_solve, initial, progress, &r);
  if (r.method != options.method) r.message += " (point-to-point: the fixed cloud has no normals)";
  r.fixed_from_moving = ToWorld(local, r.origin);
  const OverlapStats after = MeasureOverlap(index, moving_all, local, d);
  r.overlap_after = after.overlap;
  r.rms_after = after.rms;
  return r;
}

PointCloud TransformPointCloud(const Rigid3& transform, const PointCloud& cloud) {
  PointCloud out = cloud;
  const Eigen::Matrix3d r = transform.rotation.toRotationMatrix();
  const Eigen::Vector3d& o = cloud.frame.origin;
  const Eigen::Vector3d t = (r * o + transform.translation) - o;
  for (Eigen::Vector3d& p : out.positions) p = r * p + t;
  const Eigen::Matrix3f rf = r.cast<float>();
  for (Eigen::Vector3f& n : out.normals) n = rf * n;
  return out;
}

}  // namespace candi::photogrammetry

// FPFH + RANSAC with PCL. PCL's feature and sample-consensus headers live in this file only.
#include "reconstruction/photogrammetry/registration/coarse_alignment.h"

#include <pcl/features/fpfh.h>
#include <pcl/point_types.h>
#include <pcl/registration/sample_consensus_prerejective.h>
#include <pcl/search/kdtree.h>

#include <cmath>
#include <cstdlib>
#include <vector>

#include "core/check.h"
#include "core/text_format.h"
#include "reconstruction/photogrammetry/registration/cleaning.h"
#include "reconstruction/photogrammetry/registration/local_points.h"
#include "reconstruction/photogrammetry/registration/point_normals.h"

namespace candi::photogrammetry {

namespace {

using PointT = pcl::PointNormal;
using Cloud = pcl::PointCloud<PointT>;
using Features = pcl::PointCloud<pcl::FPFHSignature33>;

// The cloud thinned to `voxel`, relative to `origin`, with normals (points without one dropped).
Cloud::Ptr FeatureCloud(const CoarseAlignmentOptions& o, const PointCloud& cloud,
                        const Eigen::Vector3d& origin, const std::string& name) {
  const std::vector<Eigen::Vector3f> points =
      LocalFloatPoints(cloud, VoxelThinIndices(cloud, o.voxel), origin, name);
  const std::vector<Eigen::Vector3f> normals = EstimateNormals(points, o.normal_neighbours);
  Cloud::Ptr out(new Cloud);
  for (size_t i = 0; i < points.size(); ++i) {
    if (!normals[i].allFinite() || normals[i].squaredNorm() < 0.25f) continue;
    PointT p;
    p.getVector3fMap() = points[i];
    p.getNormalVector3fMap() = normals[i].normalized();
    out->push_back(p);
  }
  return out;
}

Features::Ptr ComputeFeatures(const CoarseAlignmentOptions& o, const Cloud::Ptr& cloud) {
  pcl::FPFHEstimation<PointT, PointT, pcl::FPFHSignature33> fpfh;
  fpfh.setInputCloud(cloud);
  fpfh.setInputNormals(cloud);
  fpfh.setSearchMethod(pcl::search::KdTree<PointT>::Ptr(new pcl::search::KdTree<PointT>));
  fpfh.setRadiusSearch(o.feature_radius);
  Features::Ptr features(new Features);
  fpfh.compute(*features);
  return features;
}

}  // namespace

void CoarseAlignmentOptions::Check() const {
  CANDI_CHECK_OPTION(std::isfinite(voxel) && voxel > 0, voxel, "finite and > 0");
  CANDI_CHECK_OPTION_IN(normal_neighbours, 3, 1000);
  CANDI_CHECK_OPTION(std::isfinite(feature_radius) && feature_radius > voxel, feature_radius,
                     "finite and > voxel");
  CANDI_CHECK_OPTION_IN(max_iterations, 1, 10000000);
  CANDI_CHECK_OPTION_IN(correspondence_randomness, 1, 100);
  CANDI_CHECK_OPTION(similarity_threshold > 0 && similarity_threshold < 1, similarity_threshold,
                     "in (0, 1)");
  CANDI_CHECK_OPTION(std::isfinite(inlier_distance) && inlier_distance > 0, inlier_distance,
                     "finite and > 0");
  CANDI_CHECK_OPTION_IN(min_inlier_fraction, 0, 1);
}

CoarseAlignmentResult CoarseAlign(const CoarseAlignmentOptions& options, const PointCloud& moving,
                                  const PointCloud& fixed) {
  options.Check();
  if (moving.empty()) throw InputError("moving cloud", "", "no points to align");
  if (fixed.empty()) throw InputError("fixed cloud", "", "no points to align onto");
  CheckFinitePositions(moving, "moving cloud");
  CheckFinitePositions(fixed, "fixed cloud");
  // One origin for both: the fixed cloud's; the moving cloud is wherever its frame puts it, so its
  // own points are re-centred too (a far-off moving cloud must not lose float precision).
  const Eigen::Vector3d origin = CommonOrigin(fixed.WorldBounds());
  const Eigen::Vector3d moving_origin = CommonOrigin(moving.WorldBounds());
  const Cloud::Ptr src = FeatureCloud(options, moving, moving_origin, "moving cloud");
  const Cloud::Ptr dst = FeatureCloud(options, fixed, origin, "fixed cloud");
  CoarseAlignmentResult r;
  r.moving_points = src->size();
  r.fixed_points = dst->size();
  if (src->size() < 3 || dst->size() < 3) {
    r.message =
        "too few points with a normal after thinning to " + FormatDouble(options.voxel) + " m";
    return r;
  }
  pcl::SampleConsensusPrerejective<PointT, PointT, pcl::FPFHSignature33> sac;
  sac.setInputSource(src);
  sac.setSourceFeatures(ComputeFeatures(options, src));
  sac.setInputTarget(dst);
  sac.setTargetFeatures(ComputeFeatures(options, dst));
  sac.setMaximumIterations(options.max_iterations);
  sac.setNumberOfSamples(3);
  sac.setCorrespondenceRandomness(options.correspondence_randomness);
  sac.setSimilarityThreshold(static_cast<float>(options.similarity_threshold));
  sac.setMaxCorrespondenceDistance(options.inlier_distance);
  sac.setInlierFraction(static_cast<float>(options.min_inlier_fraction));
  std::srand(static_cast<unsigned>(options.seed));
  Cloud aligned;
  sac.align(aligned);
  r.inlier_fraction = static_cast<double>(sac.getInliers().size()) / src->size();
  if (!sac.hasConverged()) {
    r.message = "no pose with " + FormatDouble(options.min_inlier_fraction) +
                " of the points within " + FormatDouble(options.inlier_distance) + " m after " +
                std::to_string(options.max_iterations) + " iterations";
    return r;
  }
  // local: x_dst - origin = M (x_src - moving_origin)  =>  world: R x + (t + origin - R mo).
  const Eigen::Matrix4d m = sac.getFinalTransformation().cast<double>();
  const Eigen::Matrix3d rot = m.topLeftCorner<3, 3>();
  r.fixed_from_moving =
      Rigid3(Eigen::Quaterniond(rot), m.topRightCorner<3, 1>() + origin - rot * moving_origin);
  r.found = true;
  r.message = "found: " + FormatDouble(r.inlier_fraction) + " of the moving points are inliers";
  return r;
}

}  // namespace candi::photogrammetry

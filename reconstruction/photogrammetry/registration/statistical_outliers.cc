// StatisticalInliers (cleaning.h): PCL's statistical outlier removal. PCL's filter headers live in
// this file only (they are slow to compile).
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <climits>

#include "core/check.h"
#include "reconstruction/photogrammetry/registration/cleaning.h"
#include "reconstruction/photogrammetry/registration/local_points.h"

namespace candi::photogrammetry {

std::vector<size_t> StatisticalInliers(const PointCloud& cloud, int neighbours,
                                       double std_multiplier) {
  CANDI_CHECK(neighbours >= 1) << "StatisticalInliers: neighbours = " << neighbours;
  CANDI_CHECK_LT(cloud.size(), static_cast<size_t>(INT_MAX));  // PCL's indices are int
  std::vector<size_t> kept;
  if (cloud.size() < 2) {
    CheckFinitePositions(cloud, "statistical outlier removal");
    for (size_t i = 0; i < cloud.size(); ++i) kept.push_back(i);
    return kept;
  }
  const std::vector<Eigen::Vector3f> local = LocalFloatPoints(
      cloud, CommonOrigin(cloud.WorldBounds()), "statistical outlier removal");
  pcl::PointCloud<pcl::PointXYZ>::Ptr input(new pcl::PointCloud<pcl::PointXYZ>);
  input->resize(local.size());
  for (size_t i = 0; i < local.size(); ++i) (*input)[i].getVector3fMap() = local[i];
  pcl::StatisticalOutlierRemoval<pcl::PointXYZ> sor;
  sor.setInputCloud(input);
  // PCL reads k + 1 neighbours (the point itself first): k must leave one point out.
  sor.setMeanK(std::min(neighbours, static_cast<int>(cloud.size()) - 1));
  sor.setStddevMulThresh(std_multiplier);
  pcl::Indices inliers;
  sor.filter(inliers);
  kept.assign(inliers.begin(), inliers.end());
  std::sort(kept.begin(), kept.end());
  return kept;
}

}  // namespace candi::photogrammetry

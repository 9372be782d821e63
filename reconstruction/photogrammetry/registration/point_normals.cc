// PCL's feature module lives here only (its headers are slow to compile).
#include "reconstruction/photogrammetry/registration/point_normals.h"

#include <pcl/features/normal_3d.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <limits>

#include "core/check.h"

namespace candi::photogrammetry {

std::vector<Eigen::Vector3f> EstimateNormals(const std::vector<Eigen::Vector3f>& points,
                                             int neighbours) {
  CANDI_CHECK(neighbours >= 3) << "EstimateNormals: neighbours = " << neighbours;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<Eigen::Vector3f> out(points.size(), Eigen::Vector3f::Constant(nan));
  if (points.size() < 3) return out;
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) (*cloud)[i].getVector3fMap() = points[i];
  pcl::NormalEstimation<pcl::PointXYZ, pcl::Normal> estimation;
  estimation.setInputCloud(cloud);
  estimation.setSearchMethod(pcl::search::KdTree<pcl::PointXYZ>::Ptr(
      new pcl::search::KdTree<pcl::PointXYZ>));
  estimation.setKSearch(std::min<int>(neighbours, static_cast<int>(points.size())));
  // Viewpoint far above: normals point up where they can (a deterministic sign).
  estimation.setViewPoint(0.0f, 0.0f, 1.0e7f);
  pcl::PointCloud<pcl::Normal> normals;
  estimation.compute(normals);
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3f n = normals[i].getNormalVector3fMap();
    if (n.allFinite() && n.squaredNorm() > 0.5f) out[i] = n.normalized();
  }
  return out;
}

}  // namespace candi::photogrammetry

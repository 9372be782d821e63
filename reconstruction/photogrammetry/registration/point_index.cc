// PCL's kd-tree lives here only (its headers are slow to compile).
#include "reconstruction/photogrammetry/registration/point_index.h"

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>

#include <cmath>
#include <limits>

#include "core/check.h"

namespace candi::photogrammetry {

struct PointIndex::Impl {
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud{new pcl::PointCloud<pcl::PointXYZ>};
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
};

PointIndex::PointIndex(const std::vector<Eigen::Vector3f>& points)
    : impl_(std::make_unique<Impl>()), size_(points.size()) {
  impl_->cloud->resize(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    CANDI_CHECK(points[i].allFinite()) << "PointIndex: point " << i << " is not finite";
    (*impl_->cloud)[i].getVector3fMap() = points[i];
  }
  if (!points.empty()) impl_->tree.setInputCloud(impl_->cloud);
}

PointIndex::~PointIndex() = default;

std::vector<double> PointIndex::NearestSquaredDistances(const std::vector<Eigen::Vector3f>& queries,
                                                        const Eigen::Matrix4d& transform) const {
  std::vector<double> out(queries.size(), std::numeric_limits<double>::infinity());
  if (size_ == 0) return out;
  const Eigen::Matrix3d r = transform.topLeftCorner<3, 3>();
  const Eigen::Vector3d t = transform.topRightCorner<3, 1>();
  pcl::Indices found(1);
  std::vector<float> sq(1);
  for (size_t i = 0; i < queries.size(); ++i) {
    const Eigen::Vector3d q = r * queries[i].cast<double>() + t;
    pcl::PointXYZ p;
    p.getVector3fMap() = q.cast<float>();
    if (impl_->tree.nearestKSearch(p, 1, found, sq) < 1) continue;
    // The distance again in double: float's squared distance loses digits below 1e-4 m.
    out[i] = ((*impl_->cloud)[found[0]].getVector3fMap().cast<double>() - q).squaredNorm();
  }
  return out;
}

std::pair<int64_t, double> PointIndex::Nearest(const Eigen::Vector3d& query) const {
  if (size_ == 0) return {-1, std::numeric_limits<double>::infinity()};
  pcl::Indices found(1);
  std::vector<float> sq(1);
  pcl::PointXYZ p;
  p.getVector3fMap() = query.cast<float>();
  if (impl_->tree.nearestKSearch(p, 1, found, sq) < 1) {
    return {-1, std::numeric_limits<double>::infinity()};
  }
  return {found[0], ((*impl_->cloud)[found[0]].getVector3fMap().cast<double>() - query).squaredNorm()};
}

OverlapStats MeasureOverlap(const PointIndex& index, const std::vector<Eigen::Vector3f>& queries,
                            const Eigen::Matrix4d& transform, double max_distance) {
  OverlapStats s;
  s.queries = queries.size();
  const double max_sq = max_distance * max_distance;
  double sum = 0;
  for (double d2 : index.NearestSquaredDistances(queries, transform)) {
    if (d2 > max_sq) continue;
    ++s.correspondences;
    sum += d2;
  }
  s.overlap = s.queries > 0 ? static_cast<double>(s.correspondences) / s.queries : 0.0;
  s.rms = s.correspondences > 0 ? std::sqrt(sum / s.correspondences)
                                : std::numeric_limits<double>::quiet_NaN();
  return s;
}

}  // namespace candi::photogrammetry

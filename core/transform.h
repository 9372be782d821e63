// Rigid and similarity transforms in double precision.
//
// Named target_from_source (world_from_panel): y_in_target = T * x_in_source.
// Rotation is a unit Hamilton quaternion (w, x, y, z).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

namespace candi {

struct Rigid3 {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Rigid3() = default;
  Rigid3(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) : rotation(q.normalized()), translation(t) {}

  Eigen::Vector3d operator*(const Eigen::Vector3d& x) const { return rotation * x + translation; }
  Rigid3 operator*(const Rigid3& b) const {  // (a * b)(x) = a(b(x))
    return Rigid3(rotation * b.rotation, rotation * b.translation + translation);
  }
  Rigid3 Inverse() const {
    const Eigen::Quaterniond inv = rotation.conjugate();
    return Rigid3(inv, -(inv * translation));
  }
  Eigen::Matrix4d ToMatrix() const;
};

struct Sim3 {
  double scale = 1.0;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Sim3() = default;
  Sim3(double s, const Eigen::Quaterniond& q, const Eigen::Vector3d& t);
  explicit Sim3(const Rigid3& r) : Sim3(1.0, r.rotation, r.translation) {}

  Eigen::Vector3d operator*(const Eigen::Vector3d& x) const {
    return scale * (rotation * x) + translation;
  }
  Sim3 operator*(const Sim3& b) const {
    return Sim3(scale * b.scale, rotation * b.rotation, scale * (rotation * b.translation) + translation);
  }
  Sim3 Inverse() const;
  Eigen::Matrix4d ToMatrix() const;
};

// Builds a Sim3 from a 4x4 matrix [sR t; 0 1]. Throws std::invalid_argument when the upper 3x3
// block is not a positive scale times a rotation (to `tolerance`, relative).
Sim3 Sim3FromMatrix(const Eigen::Matrix4d& m, double tolerance = 1e-9);

}  // namespace candi

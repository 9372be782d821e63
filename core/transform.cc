#include "core/transform.h"

#include <cmath>
#include <stdexcept>

#include "core/check.h"

namespace candi {

Eigen::Matrix4d Rigid3::ToMatrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = rotation.toRotationMatrix();
  m.topRightCorner<3, 1>() = translation;
  return m;
}

Sim3::Sim3(double s, const Eigen::Quaterniond& q, const Eigen::Vector3d& t)
    : scale(s), rotation(q.normalized()), translation(t) {
  CANDI_CHECK(std::isfinite(s) && s > 0.0) << "Sim3 scale = " << s << "; must be > 0";
}

Sim3 Sim3::Inverse() const {
  const Eigen::Quaterniond inv = rotation.conjugate();
  return Sim3(1.0 / scale, inv, -(inv * translation) / scale);
}

Eigen::Matrix4d Sim3::ToMatrix() const {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.topLeftCorner<3, 3>() = scale * rotation.toRotationMatrix();
  m.topRightCorner<3, 1>() = translation;
  return m;
}

Sim3 Sim3FromMatrix(const Eigen::Matrix4d& m, double tolerance) {
  if (!m.allFinite()) throw std::invalid_argument("Sim3FromMatrix: matrix has non-finite entries");
  const Eigen::RowVector4d last = m.row(3);
  if ((last - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > tolerance) {
    throw std::invalid_argument("Sim3FromMatrix: last row must be 0 0 0 1");
  }
  const Eigen::Matrix3d a = m.topLeftCorner<3, 3>();
  const double det = a.determinant();
  if (!(det > 0.0)) throw std::invalid_argument("Sim3FromMatrix: determinant must be > 0 (no reflection)");
  const double s = std::cbrt(det);
  const Eigen::Matrix3d r = a / s;
  if ((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > tolerance * 10) {
    throw std::invalid_argument("Sim3FromMatrix: upper 3x3 block is not scale * rotation");
  }
  return Sim3(s, Eigen::Quaterniond(r), m.topRightCorner<3, 1>());
}

}  // namespace candi

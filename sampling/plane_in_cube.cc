#include "sampling/plane_in_cube.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "core/check.h"

namespace candi::sampling {

namespace {

Eigen::Vector3d CubeVertex(int bits) {
  return Eigen::Vector3d(bits & 1, (bits >> 1) & 1, (bits >> 2) & 1);
}

// The section polygon's vertices: where the plane crosses the cube's 12 edges.
std::vector<Eigen::Vector3d> SectionVertices(const Eigen::Vector3d& n, double t) {
  std::vector<Eigen::Vector3d> points;
  for (int a = 0; a < 8; ++a) {
    for (int axis = 0; axis < 3; ++axis) {
      if (a & (1 << axis)) continue;  // each edge once, from its lower end
      const Eigen::Vector3d p = CubeVertex(a), q = CubeVertex(a | (1 << axis));
      const double dp = n.dot(p) - t, dq = n.dot(q) - t;
      if ((dp > 0 && dq > 0) || (dp < 0 && dq < 0) || dp == dq) continue;
      points.push_back(p + (q - p) * (dp / (dp - dq)));
    }
  }
  return points;
}

}  // namespace

double PlaneInCubeArea(const Eigen::Vector3d& unit_normal, double offset) {
  std::vector<Eigen::Vector3d> points = SectionVertices(unit_normal, offset);
  if (points.size() < 3) return 0.0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) centre += p;
  centre /= static_cast<double>(points.size());
  // Order the (convex) polygon by angle around its centre, in a basis of the plane.
  const Eigen::Vector3d e1 = (points[0] - centre).norm() > 0 ? (points[0] - centre).normalized()
                                                             : unit_normal.unitOrthogonal();
  const Eigen::Vector3d e2 = unit_normal.cross(e1);
  std::sort(points.begin(), points.end(), [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::atan2((a - centre).dot(e2), (a - centre).dot(e1)) <
           std::atan2((b - centre).dot(e2), (b - centre).dot(e1));
  });
  double twice_area = 0.0;
  for (size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector3d& a = points[k] - centre;
    const Eigen::Vector3d& b = points[(k + 1) % points.size()] - centre;
    twice_area += a.cross(b).dot(unit_normal);
  }
  return 0.5 * std::abs(twice_area);
}

double SizeBiasedPlaneInCubeArea(const Eigen::Vector3d& normal) {
  CANDI_CHECK(normal.allFinite() && normal.norm() > 0) << "normal = " << normal.transpose();
  const Eigen::Vector3d n = normal.normalized();
  std::array<double, 8> breaks;
  for (int v = 0; v < 8; ++v) breaks[v] = n.dot(CubeVertex(v));
  std::sort(breaks.begin(), breaks.end());
  // 3-point Gauss-Legendre on [-1, 1]: exact for A(t)^2, a quartic on each piece.
  static const double kNodes[3] = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)};
  static const double kWeights[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
  double integral = 0.0;
  for (int k = 0; k + 1 < 8; ++k) {
    const double half = 0.5 * (breaks[k + 1] - breaks[k]);
    if (!(half > 0)) continue;
    const double mid = 0.5 * (breaks[k + 1] + breaks[k]);
    for (int q = 0; q < 3; ++q) {
      const double area = PlaneInCubeArea(n, mid + half * kNodes[q]);
      integral += half * kWeights[q] * area * area;
    }
  }
  return integral;
}

}  // namespace candi::sampling

#include "sampling/plane_in_cube.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <map>
#include <tuple>
#include <vector>

#include "core/check.h"
#include "core/rng.h"

namespace candi::sampling {
namespace {

TEST(PlaneInCubeArea, KnownSections) {
  const Eigen::Vector3d z(0, 0, 1);
  EXPECT_NEAR(PlaneInCubeArea(z, 0.5), 1.0, 1e-12);
  EXPECT_EQ(PlaneInCubeArea(z, 1.5), 0.0);
  // 45° about x: the section through the centre is a 1 x √2 rectangle.
  EXPECT_NEAR(PlaneInCubeArea(Eigen::Vector3d(0, 1, 1).normalized(), std::sqrt(0.5)),
              std::sqrt(2.0), 1e-12);
  // The regular hexagon through the centre, normal (1,1,1): side √2/2, area 3√3/4.
  EXPECT_NEAR(PlaneInCubeArea(Eigen::Vector3d(1, 1, 1).normalized(), std::sqrt(3.0) / 2),
              3.0 * std::sqrt(3.0) / 4.0, 1e-12);
}

TEST(PlaneInCubeArea, IntegratesToTheVolume) {
  // ∫ A(t) dt = 1 (Cavalieri); midpoint rule on a fine grid.
  const Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  const double lo = std::min(0.0, n.x()) + std::min(0.0, n.y()) + std::min(0.0, n.z());
  const double hi = std::max(0.0, n.x()) + std::max(0.0, n.y()) + std::max(0.0, n.z());
  const int steps = 20000;
  double sum = 0;
  for (int k = 0; k < steps; ++k) sum += PlaneInCubeArea(n, lo + (hi - lo) * (k + 0.5) / steps);
  EXPECT_NEAR(sum * (hi - lo) / steps, 1.0, 1e-6);
}

TEST(SizeBiasedPlaneInCubeArea, ClosedFormsAndSymmetry) {
  EXPECT_NEAR(SizeBiasedPlaneInCubeArea(Eigen::Vector3d(0, 0, 2)), 1.0, 1e-12);
  EXPECT_NEAR(SizeBiasedPlaneInCubeArea(Eigen::Vector3d(0, 1, 1)), 2.0 * std::sqrt(2.0) / 3.0, 1e-12);
  const double g = SizeBiasedPlaneInCubeArea(Eigen::Vector3d(0.2, 0.3, 0.9));
  EXPECT_NEAR(SizeBiasedPlaneInCubeArea(Eigen::Vector3d(-0.9, 0.2, -0.3)), g, 1e-12);
  EXPECT_NEAR(SizeBiasedPlaneInCubeArea(Eigen::Vector3d(2, 1, 0)), 0.9317, 1e-4);  // the minimum
  EXPECT_THROW(SizeBiasedPlaneInCubeArea(Eigen::Vector3d::Zero()), InternalError);
}

TEST(SizeBiasedPlaneInCubeArea, PredictsTheCountInAPointsCell) {
  // Monte Carlo: random points on a tilted plane, binned into unit cells; the mean number of
  // other points in a point's cell, over the density, is G(n).
  const Eigen::Vector3d n = Eigen::Vector3d(1, 2, 3).normalized();
  const Eigen::Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  Rng rng(9);
  const double side = 40.0, density = 50.0;
  const int count = static_cast<int>(side * side * density);
  std::vector<std::tuple<int, int, int>> cells(count);
  std::vector<bool> interior(count);
  for (int k = 0; k < count; ++k) {
    const double a = rng.Uniform(0, side), b = rng.Uniform(0, side);
    const Eigen::Vector3d p = e1 * a + e2 * b + n * 0.37;
    cells[k] = {static_cast<int>(std::floor(p.x())), static_cast<int>(std::floor(p.y())),
                static_cast<int>(std::floor(p.z()))};
    // A cell's diameter is √3 < 2: cells of interior points lie wholly inside the square.
    interior[k] = a > 2 && a < side - 2 && b > 2 && b < side - 2;
  }
  std::map<std::tuple<int, int, int>, int> per_cell;
  for (const auto& c : cells) ++per_cell[c];
  double others = 0, used = 0;
  for (int k = 0; k < count; ++k) {
    if (!interior[k]) continue;
    others += per_cell[cells[k]] - 1;
    ++used;
  }
  // ~72k interior points with ~43 others each: the statistical error is well below 1 %.
  EXPECT_NEAR(others / used / density, SizeBiasedPlaneInCubeArea(n), 0.01);
}

}  // namespace
}  // namespace candi::sampling

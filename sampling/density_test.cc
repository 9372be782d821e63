#include "sampling/density.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <Eigen/Geometry>
#include <atomic>
#include <cmath>
#include <stdexcept>

#include "core/check.h"
#include "core/rng.h"

namespace candi::sampling {
namespace {

constexpr double kPi = 3.14159265358979323846;

// n points uniform on a side x side square in the plane through `offset` with normal `normal`;
// in-plane coordinates in *ab. Coordinates are rounded to 2^-20 m so that adding a survey offset
// below 2^21 m is exact.
PointCloud Plane(size_t n, double side, const Eigen::Vector3d& normal, uint64_t seed,
                 std::vector<Eigen::Vector2d>* ab = nullptr,
                 const Eigen::Vector3d& offset = Eigen::Vector3d::Zero()) {
  const Eigen::Vector3d z = normal.normalized();
  const Eigen::Vector3d x = z.unitOrthogonal(), y = z.cross(x);
  PointCloud cloud;
  cloud.Resize(n);
  if (ab) ab->resize(n);
  Rng rng(seed);
  for (size_t i = 0; i < n; ++i) {
    const double a = rng.Uniform(0, side), b = rng.Uniform(0, side);
    const Eigen::Vector3d p = (x * a + y * b) * 1048576.0;
    cloud.positions[i] = p.array().round().matrix() / 1048576.0 + offset;
    if (ab) (*ab)[i] = Eigen::Vector2d(a, b);
  }
  return cloud;
}

// Mean density of the points at least `margin` from the square's edges.
double InteriorMean(const DensityResult& r, const std::vector<Eigen::Vector2d>& ab, double side,
                    double margin) {
  double sum = 0;
  size_t used = 0;
  for (size_t i = 0; i < ab.size(); ++i) {
    if (ab[i].minCoeff() < margin || ab[i].maxCoeff() > side - margin) continue;
    sum += r.density[i];
    ++used;
  }
  return sum / static_cast<double>(used);
}

DensityOptions Method(DensityMethod method) {
  DensityOptions o;
  o.method = method;
  return o;
}

class DensityMethods : public ::testing::TestWithParam<DensityMethod> {};

TEST(DensityOptions, DefaultsPassAndBadValuesNameTheField) {
  EXPECT_NO_THROW(DensityOptions().Check());
  DensityOptions o;
  o.radius = -1;
  try {
    o.Check();
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "DensityOptions::radius = -1; must be finite and >= 0 (0 = automatic)");
  }
  o = {};
  o.target_neighbours = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.threads = -2;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  EXPECT_EQ(ParseDensityMethod("voxel"), DensityMethod::kVoxel);
  EXPECT_EQ(DensityMethodName(ParseDensityMethod("kdtree")), "kdtree");
  EXPECT_THROW(ParseDensityMethod("octree"), std::invalid_argument);
}

TEST_P(DensityMethods, UniformPlaneWithinThreePercent) {
  // 200k points on 10 x 10 m: 2000 points/m^2. An axis-aligned plane, a generic tilt, and walls
  // whose normals have rational ratios (the voxel grid meets them at a few offsets only).
  for (const Eigen::Vector3d& normal : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(1, 2, 3),
                                        Eigen::Vector3d(2, 1, 0), Eigen::Vector3d(1, 1, 0)}) {
    std::vector<Eigen::Vector2d> ab;
    const PointCloud cloud = Plane(200000, 10.0, normal, 3, &ab);
    const DensityResult r = EstimateSurfaceDensity(Method(GetParam()), cloud);
    ASSERT_EQ(r.density.size(), cloud.size());
    EXPECT_TRUE(r.automatic_radius);
    EXPECT_NEAR(r.area, kPi * r.radius * r.radius, 1e-12);
    // Median point with ~32 neighbours: pi r^2 * 2000 ≈ 32.
    EXPECT_NEAR(kPi * r.radius * r.radius * 2000.0, 32.0, 3.0) << normal.transpose();
    EXPECT_NEAR(InteriorMean(r, ab, 10.0, 0.5) / 2000.0, 1.0, 0.03) << normal.transpose();
    EXPECT_NEAR(r.median_density / 2000.0, 1.0, 0.2);
  }
}

TEST_P(DensityMethods, ExplicitRadiusIsUsed) {
  std::vector<Eigen::Vector2d> ab;
  const PointCloud cloud = Plane(50000, 5.0, Eigen::Vector3d(0, 0, 1), 4, &ab);
  DensityOptions o = Method(GetParam());
  o.radius = 0.1;
  const DensityResult r = EstimateSurfaceDensity(o, cloud);
  EXPECT_FALSE(r.automatic_radius);
  EXPECT_EQ(r.radius, 0.1);
  if (GetParam() == DensityMethod::kVoxel) {
    EXPECT_NEAR(r.cell_size, std::sqrt(kPi) * 0.1, 1e-15);
  }
  EXPECT_NEAR(InteriorMean(r, ab, 5.0, 0.3) / 2000.0, 1.0, 0.03);
}

TEST_P(DensityMethods, EmptySingleAndCoincident) {
  const DensityResult empty = EstimateSurfaceDensity(Method(GetParam()), PointCloud());
  EXPECT_TRUE(empty.density.empty());
  EXPECT_EQ(empty.median_density, 0.0);

  PointCloud one;
  one.positions = {Eigen::Vector3d(3, 4, 5)};
  const DensityResult single = EstimateSurfaceDensity(Method(GetParam()), one);
  ASSERT_EQ(single.density.size(), 1u);
  EXPECT_EQ(single.density[0], 0.0) << "no other point";
  EXPECT_EQ(single.radius, 1.0) << "the documented fallback for a cloud of one spot";

  PointCloud same;
  same.positions.assign(1000, Eigen::Vector3d(1e6, 2e6, 3));
  const DensityResult coincident = EstimateSurfaceDensity(Method(GetParam()), same);
  ASSERT_EQ(coincident.density.size(), 1000u);
  for (double d : coincident.density) {
    ASSERT_TRUE(std::isfinite(d));
    // Each point has 999 others within any radius; radius falls back to 1 m.
    ASSERT_NEAR(d, 999.0 / kPi, 1e-9);
  }
}

TEST_P(DensityMethods, NonFinitePositionIsACallerError) {
  PointCloud cloud = Plane(100, 1.0, Eigen::Vector3d(0, 0, 1), 5);
  cloud.positions[17].y() = std::nan("");
  try {
    EstimateSurfaceDensity(Method(GetParam()), cloud);
    ADD_FAILURE() << "no throw";
  } catch (const InternalError& e) {
    EXPECT_NE(std::string(e.what()).find("point 17 has a non-finite position"), std::string::npos)
        << e.what();
  }
}

TEST_P(DensityMethods, SurveyScaleOffsetGivesTheSameDensities) {
  const Eigen::Vector3d normal(0.2, 0.1, 1.0);
  const PointCloud near = Plane(20000, 10.0, normal, 6);
  const PointCloud far = Plane(20000, 10.0, normal, 6, nullptr, Eigen::Vector3d(1e6, 2e6, 100));
  ASSERT_TRUE(far.frame.IsIdentity());
  const DensityResult a = EstimateSurfaceDensity(Method(GetParam()), near);
  const DensityResult b = EstimateSurfaceDensity(Method(GetParam()), far);
  EXPECT_NEAR(b.radius / a.radius, 1.0, 1e-6);
  for (size_t i = 0; i < a.density.size(); ++i) {
    ASSERT_NEAR(b.density[i], a.density[i], 1e-6 * a.density[i]) << i;
  }
}

TEST_P(DensityMethods, IdenticalForAnyThreadCount) {
  const PointCloud cloud = Plane(60000, 6.0, Eigen::Vector3d(1, 1, 3), 7);
  std::vector<double> serial, parallel, arena;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    serial = EstimateSurfaceDensity(Method(GetParam()), cloud).density;
  }
  {
    tbb::global_control two(tbb::global_control::max_allowed_parallelism, 2);
    parallel = EstimateSurfaceDensity(Method(GetParam()), cloud).density;
  }
  DensityOptions o = Method(GetParam());
  o.threads = 2;
  arena = EstimateSurfaceDensity(o, cloud).density;
  EXPECT_EQ(serial, parallel);
  EXPECT_EQ(serial, arena);
  o.seed = 99;  // another radius sample: a slightly different radius, so different densities
  EXPECT_NE(EstimateSurfaceDensity(o, cloud).density, serial);
}

TEST_P(DensityMethods, WeightsCountAsCopies) {
  // Each point with weight 2 must give the densities of the cloud holding it twice (the voxel
  // plane fit sees the duplicates, so equal to rounding there: 1e-9).
  const PointCloud base = Plane(5000, 2.0, Eigen::Vector3d(0, 1, 2), 8);
  PointCloud doubled = base;
  doubled.Append(base);
  PointCloud weighted = base;
  const int w = weighted.AddScalarField("spbr_multiplicity");
  for (size_t i = 0; i < weighted.size(); ++i) weighted.scalars[w].Set(i, 2.0);
  DensityOptions o = Method(GetParam());
  o.radius = 0.05;
  const DensityResult plain = EstimateSurfaceDensity(o, doubled);
  o.weight_field = "spbr_multiplicity";
  const DensityResult counted = EstimateSurfaceDensity(o, weighted);
  for (size_t i = 0; i < base.size(); ++i) {
    ASSERT_NEAR(counted.density[i], plain.density[i], 1e-9 * plain.density[i]) << i;
  }
  weighted.scalars[w].Set(3, -1.0);
  EXPECT_THROW(EstimateSurfaceDensity(o, weighted), InputError);
  o.weight_field = "nope";
  EXPECT_THROW(EstimateSurfaceDensity(o, weighted), std::invalid_argument);
}

TEST_P(DensityMethods, ReportsProgressUpToTheTotal) {
  const PointCloud cloud = Plane(30000, 3.0, Eigen::Vector3d(0, 0, 1), 9);
  std::atomic<uint64_t> last_total{0}, max_done{0};
  DensityOptions o = Method(GetParam());
  o.progress = [&](uint64_t done, uint64_t total) {
    last_total = total;
    uint64_t seen = max_done.load();
    while (done > seen && !max_done.compare_exchange_weak(seen, done)) {
    }
  };
  EstimateSurfaceDensity(o, cloud);
  EXPECT_EQ(last_total.load(), cloud.size());
  EXPECT_EQ(max_done.load(), cloud.size());
}

INSTANTIATE_TEST_SUITE_P(Both, DensityMethods,
                         ::testing::Values(DensityMethod::kKdTree, DensityMethod::kVoxel),
                         [](const auto& info) { return DensityMethodName(info.param); });

}  // namespace
}  // namespace candi::sampling

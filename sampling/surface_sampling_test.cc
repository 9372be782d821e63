#include "sampling/surface_sampling.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "core/check.h"

namespace candi::sampling {
namespace {

// The unit square z = 0 cut into very unequal triangles: a fan from (0.01, 0.01) to a boundary
// divided unevenly, so per-triangle sampling is far from uniform.
TriMesh UnevenSquare() {
  TriMesh m;
  std::vector<Eigen::Vector3d>& p = m.vertices.positions;
  p.emplace_back(0.01, 0.01, 0);
  std::vector<double> cuts = {0, 0.02, 0.05, 0.3, 1.0};
  for (double c : cuts) p.emplace_back(c, 0, 0);                                   // bottom edge
  for (size_t k = 1; k < cuts.size(); ++k) p.emplace_back(1, cuts[k], 0);          // right edge
  for (size_t k = 1; k < cuts.size(); ++k) p.emplace_back(1 - cuts[k], 1, 0);      // top edge
  for (size_t k = 1; k + 1 < cuts.size(); ++k) p.emplace_back(0, 1 - cuts[k], 0);  // left
  const uint32_t ring = static_cast<uint32_t>(p.size() - 1);
  for (uint32_t k = 1; k <= ring; ++k) m.faces.push_back({0, k, k % ring + 1});
  m.vertices.Resize(p.size());
  return m;
}

// The chi-square statistic of counts in a g x g grid of equal cells of the unit square, and its
// 1 % critical value (Wilson-Hilferty; df = g^2 - 1).
struct ChiSquare {
  double statistic = 0, critical = 0;
};
ChiSquare GridChiSquare(const PointCloud& cloud, int g) {
  std::vector<double> counts(static_cast<size_t>(g * g), 0.0);
  for (const Eigen::Vector3d& q : cloud.positions) {
    const int i = std::min(g - 1, static_cast<int>(q.x() * g));
    const int j = std::min(g - 1, static_cast<int>(q.y() * g));
    counts[static_cast<size_t>(i * g + j)] += 1;
  }
  const double expected = static_cast<double>(cloud.size()) / (g * g);
  ChiSquare c;
  for (double n : counts) c.statistic += (n - expected) * (n - expected) / expected;
  const double df = g * g - 1, z99 = 2.3263478740408408;
  c.critical = df * std::pow(1 - 2 / (9 * df) + z99 * std::sqrt(2 / (9 * df)), 3);
  return c;
}

TEST(SurfaceSampleOptions, DefaultsNeedACountOrDensityAndBadValuesNameTheField) {
  SurfaceSampleOptions o;
  EXPECT_THROW(o.Check(), std::invalid_argument) << "neither count nor density";
  o.count = 10;
  EXPECT_NO_THROW(o.Check());
  o.density = 1;
  try {
    o.Check();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("exactly one of count and density"), std::string::npos);
  }
  o = {};
  o.mode = SurfaceSamplingMode::kPerTriangle;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o.per_triangle = 3;
  EXPECT_NO_THROW(o.Check());
}

TEST(SampleSurface, ExactCountAndDensityCount) {
  const TriMesh mesh = UnevenSquare();
  EXPECT_NEAR(MeshArea(mesh), 1.0, 1e-12);
  SurfaceSampleOptions o;
  o.count = 12345;
  EXPECT_EQ(SampleSurface(o, mesh).size(), 12345u);
  o.count = 0;
  o.density = 777.4;
  EXPECT_EQ(SampleSurface(o, mesh).size(), 777u);
}

TEST(SampleSurface, AreaSamplingPassesChiSquareOnEqualCellsPerTriangleDoesNot) {
  const TriMesh mesh = UnevenSquare();
  SurfaceSampleOptions o;
  o.count = 200000;
  for (uint64_t seed : {1, 2, 3}) {
    o.seed = seed;
    const ChiSquare c = GridChiSquare(SampleSurface(o, mesh), 10);
    EXPECT_LT(c.statistic, c.critical) << "seed " << seed;
  }
  SurfaceSampleOptions paper;
  paper.mode = SurfaceSamplingMode::kPerTriangle;
  paper.per_triangle = 20000;
  const ChiSquare c = GridChiSquare(SampleSurface(paper, mesh), 10);
  EXPECT_GT(c.statistic, 100 * c.critical) << "equal counts in unequal triangles";
}

TEST(SampleSurface, SameOutputForAnyThreadCountNewOutputForANewSeed) {
  const TriMesh mesh = UnevenSquare();
  SurfaceSampleOptions o;
  o.count = 100000;
  o.threads = 1;
  const PointCloud one = SampleSurface(o, mesh);
  o.threads = 2;
  const PointCloud two = SampleSurface(o, mesh);
  EXPECT_EQ(one.positions, two.positions);
  o.seed = 9;
  EXPECT_NE(SampleSurface(o, mesh).positions, one.positions);
}

TEST(SampleSurface, PointsLieOnTheMeshWithNormalsColourLayerAndFrame) {
  TriMesh mesh;
  mesh.vertices.Resize(3);
  mesh.vertices.positions = {{0, 0, 0}, {2, 0, 2}, {0, 3, 0}};
  mesh.vertices.frame.origin = Eigen::Vector3d(500000, 4000000, 100);
  mesh.faces = {{0, 1, 2}};
  SurfaceSampleOptions o;
  o.count = 1000;
  o.colour = Rgb8{10, 200, 30};
  o.layer = 3;
  const PointCloud c = SampleSurface(o, mesh);
  EXPECT_EQ(c.frame, mesh.vertices.frame);
  const Eigen::Vector3d n = Eigen::Vector3d(-1, 0, 1).normalized();
  for (size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3d& q = c.positions[i];
    EXPECT_NEAR(q.x(), q.z(), 1e-12);
    EXPECT_GE(q.y(), -1e-12);
    EXPECT_LE(q.x() / 2 + q.y() / 3, 1 + 1e-12);
    EXPECT_NEAR((c.normals[i].cast<double>() - n).norm(), 0, 1e-6);
    EXPECT_EQ(c.colors[i], (Rgb8{10, 200, 30}));
    EXPECT_EQ(c.layers[i], 3);
  }
}

TEST(SampleSurface, ZeroAreaMeshIsAnInputError) {
  TriMesh mesh;
  mesh.vertices.Resize(3);
  mesh.vertices.positions = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}};
  mesh.faces = {{0, 1, 2}};
  SurfaceSampleOptions o;
  o.count = 5;
  EXPECT_THROW(SampleSurface(o, mesh), InputError);
}

TEST(SplitCount, SplitsExactlyInProportion) {
  const std::vector<uint64_t> parts = SplitCount(4470000, {716.0, 661.5, 1266.9, 1823.0});
  EXPECT_EQ(parts[0] + parts[1] + parts[2] + parts[3], 4470000u);
  EXPECT_NEAR(static_cast<double>(parts[0]), 4470000 * 716.0 / 4467.4, 1.0);
  EXPECT_EQ(SplitCount(10, {1, 1, 1}), (std::vector<uint64_t>{4, 3, 3}));
  EXPECT_THROW(SplitCount(10, {0, 0}), InternalError);
}

}  // namespace
}  // namespace candi::sampling

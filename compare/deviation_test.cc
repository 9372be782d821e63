#include "compare/deviation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "compare/report.h"
#include "core/check.h"
#include "core/rng.h"

namespace candi::compare {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

PointCloud Cloud(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector3d& origin = {0, 0, 0}) {
  PointCloud c;
  c.frame.origin = origin;
  c.positions = pts;
  return c;
}

// A square patch [0, size]^2 at height z with Gaussian noise sigma along z, on a jittered grid.
std::vector<Eigen::Vector3d> Patch(double size, double spacing, double z, double sigma, uint64_t seed) {
  Rng rng(seed);
  std::vector<Eigen::Vector3d> pts;
  const int n = static_cast<int>(size / spacing);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      pts.emplace_back((i + rng.Uniform()) * spacing, (j + rng.Uniform()) * spacing,
                       z + sigma * rng.Normal());
    }
  }
  return pts;
}

DeviationOptions Options(Method m) {
  DeviationOptions o;
  o.method = m;
  return o;
}

DeviationResult C2c(const PointCloud& ref, const PointCloud& cmp, DeviationOptions o = Options(Method::kC2C)) {
  return CompareToCloud(o, ref, cmp, "ref.ply", "cmp.ply");
}

TEST(C2cTest, EqualsBruteForceNearestDistance) {
  Rng rng(3);
  std::vector<Eigen::Vector3d> a, b;
  for (int i = 0; i < 3000; ++i) a.emplace_back(rng.Uniform(0, 5), rng.Uniform(0, 5), rng.Uniform(0, 1));
  for (int i = 0; i < 700; ++i) b.emplace_back(rng.Uniform(-1, 6), rng.Uniform(-1, 6), rng.Uniform(-1, 2));
  const DeviationResult r = C2c(Cloud(a), Cloud(b));
  ASSERT_EQ(r.distance.size(), b.size());
  for (size_t i = 0; i < b.size(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& p : a) best = std::min(best, (p - b[i]).norm());
    EXPECT_NEAR(r.distance[i], best, 1e-15) << i;  // about the common origin: rounding
  }
  EXPECT_EQ(r.undefined, 0u);
  EXPECT_TRUE(r.lod95.empty());
}

TEST(C2cTest, SameBytesOnOneAndTwoThreads) {
  const auto ref = Cloud(Patch(4, 0.02, 0, 0.003, 1));
  const auto cmp = Cloud(Patch(4, 0.03, 0.01, 0.003, 2));
  for (LocalModel model : {LocalModel::kNone, LocalModel::kPlane, LocalModel::kQuadric}) {
    DeviationOptions o = Options(Method::kC2C);
    o.c2c.local_model = model;
    o.threads = 1;
    const auto one = C2c(ref, cmp, o);
    o.threads = 2;
    const auto two = C2c(ref, cmp, o);
    EXPECT_EQ(one.distance, two.distance) << LocalModelName(model);
  }
}

TEST(C2cTest, PlaneModelMeasuresToTheSurfaceNotToItsSamples) {
  // A reference sampled at 0.1 m; compared points 1 cm above, between the samples.
  std::vector<Eigen::Vector3d> ref;
  for (int i = -10; i <= 10; ++i)
    for (int j = -10; j <= 10; ++j) ref.emplace_back(0.1 * i, 0.1 * j, 0);
  std::vector<Eigen::Vector3d> cmp = {{0.05, 0.05, 0.01}, {0.23, -0.41, 0.01}, {0.0, 0.0, 0.01}};
  const auto plain = C2c(Cloud(ref), Cloud(cmp));
  EXPECT_NEAR(plain.distance[0], std::sqrt(0.05 * 0.05 * 2 + 1e-4), 1e-12);
  DeviationOptions o = Options(Method::kC2C);
  o.c2c.local_model = LocalModel::kPlane;
  const auto model = C2c(Cloud(ref), Cloud(cmp), o);
  for (double d : model.distance) EXPECT_NEAR(d, 0.01, 1e-12);
  EXPECT_EQ(model.model_fallbacks, 0u);
}

TEST(C2cTest, QuadricModelFollowsACurvedReference) {
  // A sphere of radius 1 sampled at ~3 cm; compared points 5 mm outside it.
  std::vector<Eigen::Vector3d> ref, cmp;
  Rng rng(5);
  for (int i = 0; i < 14000; ++i) {
    Eigen::Vector3d p(rng.Normal(), rng.Normal(), rng.Normal());
    ref.push_back(p.normalized());
  }
  for (int i = 0; i < 300; ++i) {
    Eigen::Vector3d p(rng.Normal(), rng.Normal(), rng.Normal());
    cmp.push_back(1.005 * p.normalized());
  }
  DeviationOptions o = Options(Method::kC2C);
  o.c2c.local_model = LocalModel::kQuadric;
  o.c2c.model_neighbours = 20;
  const auto quadric = C2c(Cloud(ref), Cloud(cmp), o);
  const auto plain = C2c(Cloud(ref), Cloud(cmp));
  double err_quadric = 0, err_plain = 0;
  for (size_t i = 0; i < cmp.size(); ++i) {
    err_quadric = std::max(err_quadric, std::abs(quadric.distance[i] - 0.005));
    err_plain = std::max(err_plain, std::abs(plain.distance[i] - 0.005));
  }
  EXPECT_LT(err_quadric, 3e-4);
  EXPECT_GT(err_plain, 5e-3);  // the nearest sample is centimetres away
}

TEST(C2cTest, DegenerateNeighbourhoodFallsBackAndIsCounted) {
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 50; ++i) line.emplace_back(0.1 * i, 0, 0);  // collinear: no plane
  DeviationOptions o = Options(Method::kC2C);
  o.c2c.local_model = LocalModel::kPlane;
  const auto r = C2c(Cloud(line), Cloud({{1.0, 0.3, 0.4}}), o);
  EXPECT_NEAR(r.distance[0], 0.5, 1e-12);
  EXPECT_EQ(r.model_fallbacks, 1u);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings[0].find("collinear"), std::string::npos);
  // Coincident reference points: the same.
  const auto same = C2c(Cloud(std::vector<Eigen::Vector3d>(20, Eigen::Vector3d(1, 1, 1))),
                        Cloud({{1, 1, 2}}), o);
  EXPECT_EQ(same.distance[0], 1.0);
  EXPECT_EQ(same.model_fallbacks, 1u);
}

TEST(C2cTest, SurveyCoordinatesKeepMicrometres) {
  const Eigen::Vector3d far(512345.0, 9123456.0, 250.0);
  const auto ref_pts = Patch(2, 0.02, 0, 0.002, 7);
  const auto cmp_pts = Patch(2, 0.05, 0.004, 0.002, 8);
  const auto local = C2c(Cloud(ref_pts), Cloud(cmp_pts));
  // The same points, stored in world coordinates (no shift) and with two different shifts.
  std::vector<Eigen::Vector3d> ref_world, cmp_world;
  for (const auto& p : ref_pts) ref_world.push_back(p + far);
  for (const auto& p : cmp_pts) cmp_world.push_back(p + far - Eigen::Vector3d(300, 0, 0));
  const auto world = C2c(Cloud(ref_world), Cloud(cmp_world, {300, 0, 0}));
  for (size_t i = 0; i < cmp_pts.size(); ++i) EXPECT_NEAR(world.distance[i], local.distance[i], 1e-8);
}

TEST(C2cTest, BadInput) {
  const auto ref = Cloud(Patch(1, 0.1, 0, 0, 1));
  EXPECT_THROW(C2c(Cloud({}), ref), InputError);
  EXPECT_THROW(C2c(ref, Cloud({})), InputError);
  try {
    C2c(Cloud({}), ref);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ref.ply"), std::string::npos) << e.what();
  }
  // NaN in the compared cloud: a NaN distance, counted and stated; in the reference: left out.
  auto cmp = Cloud({{0.5, 0.5, 0.1}, {kNaN, 0, 0}});
  const auto r = C2c(ref, cmp);
  EXPECT_TRUE(std::isnan(r.distance[1]));
  EXPECT_FALSE(std::isnan(r.distance[0]));
  EXPECT_EQ(r.undefined, 1u);
  auto with_nan = ref;
  with_nan.positions.push_back({kNaN, 1, 1});
  const auto r2 = C2c(with_nan, Cloud({{0.5, 0.5, 0.1}}));
  EXPECT_EQ(r2.distance[0], C2c(ref, Cloud({{0.5, 0.5, 0.1}})).distance[0]);
  ASSERT_FALSE(r2.warnings.empty());
  EXPECT_NE(r2.warnings[0].find("left out"), std::string::npos);
  EXPECT_THROW(C2c(Cloud({{kNaN, 0, 0}}), ref), InputError);
  // A flat patch raised 5 cm (its box clear of the reference's flat one): a change, no warning.
  EXPECT_TRUE(C2c(ref, Cloud(Patch(1, 0.1, 0.05, 0, 2))).warnings.empty());
  // Far apart: measured, and said.
  const auto far = C2c(ref, Cloud({{1000, 0, 0}}));
  ASSERT_FALSE(far.warnings.empty());
  EXPECT_NE(far.warnings.back().find("do not overlap"), std::string::npos);
  DeviationOptions bad = Options(Method::kC2C);
  bad.c2c.local_model = LocalModel::kQuadric;
  bad.c2c.model_neighbours = 4;
  EXPECT_THROW(C2c(ref, ref, bad), std::invalid_argument);
  EXPECT_THROW(C2c(ref, ref, Options(Method::kC2M)), std::invalid_argument);
}

// --------------------------------------------------------------------------------------- C2M

TriMesh UnitCube(const Eigen::Vector3d& origin = {0, 0, 0}) {
  TriMesh m;
  m.vertices.frame.origin = origin;
  for (int i = 0; i < 8; ++i) m.vertices.positions.emplace_back(i & 1, (i >> 1) & 1, (i >> 2) & 1);
  // Counter-clockwise seen from outside.
  m.faces = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

TEST(C2mTest, SignedDistanceToACube) {
  const std::vector<Eigen::Vector3d> pts = {
      {0.5, 0.5, 1.25},   // above the top face
      {0.5, 0.5, 0.9},    // inside, near the top
      {0.5, 0.5, 0.5},    // the centre
      {1.3, 0.5, 1.4},    // outside an edge
      {1.2, 1.2, 1.2},    // outside a corner
      {-0.1, 0.5, 0.5},   // outside the left face
      {1.0, 0.5, 0.5}};   // on the surface
  const auto r = CompareToMesh(Options(Method::kC2M), UnitCube(), Cloud(pts), "cube.ply", "cmp.ply");
  EXPECT_NEAR(r.distance[0], 0.25, 1e-12);
  EXPECT_NEAR(r.distance[1], -0.1, 1e-12);
  EXPECT_NEAR(r.distance[2], -0.5, 1e-12);
  EXPECT_NEAR(r.distance[3], 0.5, 1e-12);
  EXPECT_NEAR(r.distance[4], std::sqrt(3 * 0.04), 1e-12);
  EXPECT_NEAR(r.distance[5], 0.1, 1e-12);
  EXPECT_NEAR(r.distance[6], 0.0, 1e-12);
  DeviationOptions o = Options(Method::kC2M);
  o.c2m.signed_distance = false;
  const auto u = CompareToMesh(o, UnitCube(), Cloud(pts), "cube.ply", "cmp.ply");
  EXPECT_NEAR(u.distance[1], 0.1, 1e-12);
  // Survey coordinates: the same numbers.
  const Eigen::Vector3d far(498765.0, 8765432.0, 120.0);
  std::vector<Eigen::Vector3d> world;
  for (const auto& p : pts) world.push_back(p + far);
  const auto s = CompareToMesh(Options(Method::kC2M), UnitCube(far), Cloud(world), "cube.ply", "cmp.ply");
  for (size_t i = 0; i < pts.size(); ++i) EXPECT_NEAR(s.distance[i], r.distance[i], 1e-9) << i;
  o.threads = 1;
  o.c2m.signed_distance = true;
  EXPECT_EQ(CompareToMesh(o, UnitCube(), Cloud(pts), "c", "p").distance, r.distance);
}

TEST(C2mTest, BadMeshes) {
  const auto cmp = Cloud({{0, 0, 0}});
  TriMesh none = UnitCube();
  none.faces.clear();
  try {
    CompareToMesh(Options(Method::kC2M), none, cmp, "empty.ply", "cmp.ply");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("empty.ply"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("faces"), std::string::npos);
  }
  TriMesh flat = UnitCube();
  flat.faces = {{0, 1, 1}, {0, 0, 0}};
  EXPECT_THROW(CompareToMesh(Options(Method::kC2M), flat, cmp, "flat.ply", "cmp.ply"), InputError);
  TriMesh out_of_range = UnitCube();
  out_of_range.faces.push_back({0, 1, 99});
  EXPECT_THROW(CompareToMesh(Options(Method::kC2M), out_of_range, cmp, "m.ply", "cmp.ply"), InputError);
  TriMesh some_flat = UnitCube();
  some_flat.faces.push_back({0, 1, 1});
  const auto r = CompareToMesh(Options(Method::kC2M), some_flat, Cloud({{0.5, 0.5, 2}}), "m.ply", "c.ply");
  EXPECT_NEAR(r.distance[0], 1.0, 1e-12);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings[0].find("degenerate"), std::string::npos);
}

// -------------------------------------------------------------------------------------- M3C2

struct M3c2Case {
  DeviationResult result;
  double mean = 0, mean_lod = 0, formula_lod = 0, significant_share = 0;
};

// Summaries over the core points that have a distance.
M3c2Case Summarise(const DeviationResult& r, double sigma1, double sigma2, double reg) {
  M3c2Case c;
  c.result = r;
  double n = 0, formula = 0;
  for (size_t i = 0; i < r.distance.size(); ++i) {
    if (std::isnan(r.distance[i])) continue;
    c.mean += r.distance[i];
    c.mean_lod += r.lod95[i];
    c.significant_share += r.significant[i];
    formula += 1.96 * (std::sqrt(sigma1 * sigma1 / r.reference_count[i] +
                                 sigma2 * sigma2 / r.compared_count[i]) + reg);
    n += 1;
  }
  c.mean /= n;
  c.mean_lod /= n;
  c.formula_lod = formula / n;
  c.significant_share /= n;
  return c;
}

TEST(M3c2Test, PlaneDisplacedByFiveMillimetres) {
  // 2 mm noise on both sides, a 5 mm shift; d = 0.1 m holds ~30 points of each cloud.
  const auto ref = Cloud(Patch(3, 0.016, 0.0, 0.002, 11));
  const auto cmp = Cloud(Patch(3, 0.016, 0.005, 0.002, 12));
  DeviationOptions o = Options(Method::kM3C2);
  o.m3c2.normal_scale = 0.5;
  o.m3c2.projection_scale = 0.1;
  o.m3c2.max_depth = 0.05;  // ten times the change
  const auto c = Summarise(CompareToCloud(o, ref, cmp, "ref", "cmp"), 0.002, 0.002, 0);
  EXPECT_NEAR(c.mean, 0.005, 0.0002);
  EXPECT_NEAR(c.mean_lod, c.formula_lod, 0.1 * c.formula_lod);
  EXPECT_GT(c.significant_share, 0.99);
  // Normals point up (+z), so the distance is positive.
  size_t up = 0;
  for (const auto& nrm : c.result.normals) up += nrm.z() > 0.99f ? 1 : 0;
  EXPECT_GT(up, cmp.size() * 9 / 10);
  // One and two threads: the same bytes.
  o.threads = 1;
  const auto one = CompareToCloud(o, ref, cmp, "ref", "cmp");
  o.threads = 2;
  const auto two = CompareToCloud(o, ref, cmp, "ref", "cmp");
  EXPECT_EQ(one.distance, two.distance);
  EXPECT_EQ(one.lod95, two.lod95);
}

TEST(M3c2Test, NoChangeIsNotFlagged) {
  const auto ref = Cloud(Patch(3, 0.016, 0.0, 0.002, 21));
  const auto cmp = Cloud(Patch(3, 0.016, 0.0, 0.002, 22));
  DeviationOptions o = Options(Method::kM3C2);
  o.m3c2.normal_scale = 0.5;
  o.m3c2.projection_scale = 0.1;
  o.m3c2.max_depth = 0.05;  // ten times the change
  const auto plain = Summarise(CompareToCloud(o, ref, cmp, "ref", "cmp"), 0.002, 0.002, 0);
  EXPECT_NEAR(plain.mean, 0.0, 0.0002);
  EXPECT_LT(plain.significant_share, 0.07);  // a 95 % level: ~5 % by chance, per point
  o.m3c2.registration_error = 0.001;         // a stated registration error of 1 mm
  const auto with_reg = Summarise(CompareToCloud(o, ref, cmp, "ref", "cmp"), 0.002, 0.002, 0.001);
  EXPECT_NEAR(with_reg.mean_lod, with_reg.formula_lod, 0.1 * with_reg.formula_lod);
  EXPECT_EQ(with_reg.significant_share, 0.0);
}

TEST(M3c2Test, CylinderMeasuredAlongItsNormals) {
  // A cylinder of radius 1 m, the compared one 5 mm larger; 1 mm noise. Normals point out.
  Rng rng(31);
  std::vector<Eigen::Vector3d> ref, cmp;
  for (int i = 0; i < 60000; ++i) {
    const double a = rng.Uniform(0, 2 * kPi), z = rng.Uniform(0, 2);
    ref.emplace_back((1 + 0.001 * rng.Normal()) * std::cos(a), (1 + 0.001 * rng.Normal()) * std::sin(a), z);
  }
  for (int i = 0; i < 3000; ++i) {
    const double a = rng.Uniform(0, 2 * kPi), z = rng.Uniform(0.3, 1.7);
    const double r = 1.005 + 0.001 * rng.Normal();
    cmp.emplace_back(r * std::cos(a), r * std::sin(a), z);
  }
  // The compared cloud needs points in the cylinders too: densify it like the reference.
  for (int i = 0; i < 57000; ++i) {
    const double a = rng.Uniform(0, 2 * kPi), z = rng.Uniform(0, 2);
    const double r = 1.005 + 0.001 * rng.Normal();
    cmp.emplace_back(r * std::cos(a), r * std::sin(a), z);
  }
  DeviationOptions o = Options(Method::kM3C2);
  o.m3c2.normal_scale = 0.3;
  o.m3c2.projection_scale = 0.1;
  o.m3c2.max_depth = 0.05;  // ten times the change
  o.m3c2.orientation = NormalOrientation::kOutward;
  const auto r = CompareToCloud(o, Cloud(ref), Cloud(cmp), "ref", "cmp");
  double sum = 0;
  size_t n = 0;
  for (size_t i = 0; i < 3000; ++i) {
    if (std::isnan(r.distance[i])) continue;
    sum += r.distance[i];
    ++n;
  }
  EXPECT_GT(n, 2900u);
  EXPECT_NEAR(sum / n, 0.005, 0.0003);
  // With "+z" orientation the normals are horizontal, so they fall back to +x: the sign flips
  // on the far side, and the mean is near zero. The orientation matters, as the paper warns.
  o.m3c2.orientation = NormalOrientation::kPlusZ;
  const auto wrong = CompareToCloud(o, Cloud(ref), Cloud(cmp), "ref", "cmp");
  double wrong_sum = 0;
  for (size_t i = 0; i < 3000; ++i) wrong_sum += std::isnan(wrong.distance[i]) ? 0 : wrong.distance[i];
  EXPECT_LT(std::abs(wrong_sum / n), 0.002);
}

TEST(M3c2Test, RoughnessRaisesTheLevelOfDetection) {
  DeviationOptions o = Options(Method::kM3C2);
  o.m3c2.normal_scale = 0.5;
  o.m3c2.projection_scale = 0.1;
  o.m3c2.max_depth = 0.05;  // ten times the change
  const auto smooth = Summarise(CompareToCloud(o, Cloud(Patch(2, 0.016, 0, 0.001, 41)),
                                               Cloud(Patch(2, 0.016, 0.005, 0.001, 42)), "r", "c"),
                                0.001, 0.001, 0);
  const auto rough = Summarise(CompareToCloud(o, Cloud(Patch(2, 0.016, 0, 0.005, 43)),
                                              Cloud(Patch(2, 0.016, 0.005, 0.005, 44)), "r", "c"),
                               0.005, 0.005, 0);
  EXPECT_NEAR(rough.mean_lod / smooth.mean_lod, 5.0, 0.5);
  EXPECT_NEAR(rough.mean, 0.005, 0.0005);
  EXPECT_LT(rough.significant_share, smooth.significant_share);
}

TEST(M3c2Test, UndefinedPointsAreNaNAndCounted) {
  const auto ref = Cloud(Patch(1, 0.02, 0, 0.001, 51));
  // A compared point far outside the reference: no normal; one above it but beyond max depth.
  const auto cmp = Cloud({{0.5, 0.5, 0.001}, {5, 5, 0}, {0.5, 0.5, 0.5}, {kNaN, 0, 0}, {0.51, 0.5, 0.001}});
  DeviationOptions o = Options(Method::kM3C2);
  o.m3c2.normal_scale = 0.2;
  o.m3c2.projection_scale = 0.1;
  o.m3c2.max_depth = 0.05;  // ten times the change
  o.m3c2.max_depth = 0.1;
  o.m3c2.min_points = 2;
  const auto r = CompareToCloud(o, ref, cmp, "ref", "cmp");
  EXPECT_FALSE(std::isnan(r.distance[0]));
  EXPECT_TRUE(std::isnan(r.distance[1]));
  EXPECT_TRUE(std::isnan(r.distance[2]));
  EXPECT_TRUE(std::isnan(r.distance[3]));
  EXPECT_EQ(r.undefined, 3u);
  EXPECT_EQ(r.no_normal, 2u);  // far away, and above (no reference within D/2)
  EXPECT_GE(r.warnings.size(), 2u);
  // Automatic scales: ~30 points in a cylinder of diameter d at 2500 points/m^2, D = 2 d.
  const auto [big, small] = AutoM3c2Scales(ref);
  EXPECT_NEAR(small, std::sqrt(4 * 30 / (kPi * 2500)), 0.02);
  EXPECT_DOUBLE_EQ(big, 2 * small);
}

TEST(DeviationFieldsTest, FieldsInInputOrder) {
  const auto ref = Cloud(Patch(1, 0.02, 0, 0.001, 61));
  auto cmp = Cloud(Patch(1, 0.05, 0.003, 0.001, 62));
  cmp.AddScalarField("distance");  // replaced, not duplicated
  DeviationOptions o = Options(Method::kM3C2);
  o.m3c2.normal_scale = 0.2;
  o.m3c2.projection_scale = 0.08;
  const auto r = CompareToCloud(o, ref, cmp, "r", "c");
  const PointCloud out = WithDeviationFields(cmp, r);
  ASSERT_NE(out.FindScalar("distance"), nullptr);
  EXPECT_EQ(out.schema.scalars.size(), 7u);
  EXPECT_TRUE(out.schema.normals);
  for (size_t i = 0; i < cmp.size(); ++i) {
    EXPECT_EQ(out.positions[i], cmp.positions[i]);
    const double d = out.FindScalar("distance")->Get(i);
    EXPECT_TRUE(d == static_cast<float>(r.distance[i]) || (std::isnan(d) && std::isnan(r.distance[i])));
    EXPECT_EQ(out.FindScalar("significant")->Get(i), r.significant[i]);
  }
}

TEST(SummaryTest, Figures) {
  DeviationResult r;
  r.method = Method::kC2M;
  for (int i = -50; i <= 50; ++i) r.distance.push_back(0.001 * i);
  r.distance.push_back(kNaN);
  SummaryOptions o;
  o.tolerance = 0.0105;
  o.bins = 10;
  o.range = 0.04;
  const DeviationSummary s = Summarize(r, o);
  EXPECT_EQ(s.count, 102u);
  EXPECT_EQ(s.defined, 101u);
  EXPECT_EQ(s.undefined, 1u);
  EXPECT_NEAR(s.mean, 0.0, 1e-15);
  EXPECT_NEAR(s.max, 0.05, 1e-15);
  EXPECT_NEAR(s.percentiles[3].second, 0.0, 1e-15);  // median
  EXPECT_NEAR(s.percentiles[6].second, 0.049, 1e-12);  // 99th
  EXPECT_NEAR(s.within_tolerance, 21.0 / 101.0, 1e-12);
  uint64_t sum = s.below + s.above;
  for (uint64_t b : s.bins) sum += b;
  EXPECT_EQ(sum, 101u);
  EXPECT_EQ(s.below, 10u);
  EXPECT_EQ(s.above, 10u);
  const std::string svg = HistogramSvg(s, "a <title>");
  EXPECT_NE(svg.find("a &lt;title&gt;"), std::string::npos);
  EXPECT_NE(svg.find("10 below and 10 above"), std::string::npos);
  ReportContext c;
  c.reference = "ref.ply";
  c.compared = "cmp.ply";
  c.warnings = {"a warning"};
  const std::string md = ReportMarkdown(s, c);
  EXPECT_NE(md.find("| undefined (NaN) | 1 |"), std::string::npos) << md;
  EXPECT_NE(md.find("- a warning"), std::string::npos);
  // Nothing defined: NaN figures, no crash.
  DeviationResult empty;
  empty.distance = {kNaN};
  const DeviationSummary e = Summarize(empty, {});
  EXPECT_TRUE(std::isnan(e.mean));
  EXPECT_NE(ReportMarkdown(e, c).find("n/a"), std::string::npos);
}

}  // namespace
}  // namespace candi::compare

#include "sampling/opacity.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/check.h"
#include "core/rng.h"
#include "sampling/surface_sampling.h"

namespace candi::sampling {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// ---- The law and its inverse ----

TEST(SpbrAlpha, Edges) {
  EXPECT_EQ(SpbrAlpha(0.0, 0.3), 0.0) << "no points: transparent";
  EXPECT_EQ(SpbrAlpha(2.0, 0.0), 0.0) << "points of no size";
  EXPECT_EQ(SpbrAlpha(0.5, 1.0), 1.0) << "one point covers the whole area";
  EXPECT_EQ(SpbrAlpha(1e-9, 1.0), 1.0);
  EXPECT_EQ(SpbrAlpha(0.5, 3.0), 1.0) << "s > S is treated as s = S";
  EXPECT_EQ(SpbrAlpha(kInf, 0.1), 1.0);
  EXPECT_EQ(SpbrAlpha(kInf, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(SpbrAlpha(1.0, 0.25), 0.25) << "one point per ensemble covers s/S";
  EXPECT_DOUBLE_EQ(SpbrAlpha(2.0, 0.5), 0.75);
  EXPECT_THROW(SpbrAlpha(-1.0, 0.1), InternalError);
  EXPECT_THROW(SpbrAlpha(1.0, std::nan("")), InternalError);
}

TEST(SpbrPointsPerEnsemble, Edges) {
  EXPECT_EQ(SpbrPointsPerEnsemble(0.0, 0.3), 0.0) << "alpha = 0 needs no points";
  EXPECT_EQ(SpbrPointsPerEnsemble(0.0, 0.0), 0.0);
  EXPECT_EQ(SpbrPointsPerEnsemble(1.0, 0.3), kInf) << "alpha = 1 needs infinitely many";
  EXPECT_EQ(SpbrPointsPerEnsemble(0.5, 0.0), kInf) << "points of no size never cover";
  // s/S -> 1: the inverse falls to 0 continuously; at 1 and beyond it is that limit.
  const double near_one = SpbrPointsPerEnsemble(0.5, 1.0 - 1e-12);
  EXPECT_GT(near_one, 0.0);
  EXPECT_NEAR(near_one, std::log(2.0) / -std::log(1e-12), 1e-6);
  EXPECT_LT(SpbrPointsPerEnsemble(0.5, 1.0 - 1e-15), near_one);
  EXPECT_EQ(SpbrPointsPerEnsemble(0.5, 1.0), 0.0);
  EXPECT_EQ(SpbrPointsPerEnsemble(0.5, 2.0), 0.0);
  EXPECT_EQ(SpbrPointsPerEnsemble(1.0, 1.0), kInf);
  EXPECT_THROW(SpbrPointsPerEnsemble(1.5, 0.1), InternalError);
  EXPECT_THROW(SpbrPointsPerEnsemble(0.5, -0.1), InternalError);
}

TEST(SpbrPointsPerEnsemble, InvertsSpbrAlpha) {
  for (double ratio : {1e-12, 1e-6, 1e-3, 0.05, 0.3, 0.9}) {
    for (double n : {0.01, 0.5, 1.0, 7.3, 100.0}) {
      const double alpha = SpbrAlpha(n, ratio);
      if (alpha > 0.999) continue;  // ill-conditioned: 1 - alpha keeps few digits
      EXPECT_NEAR(SpbrPointsPerEnsemble(alpha, ratio) / n, 1.0, 1e-12) << n << " " << ratio;
    }
  }
}

TEST(SpbrAlpha, KeepsFullPrecisionForTinyCoverage) {
  for (double ratio : {1e-12, 1e-9, 1e-15}) {
    for (double n : {0.5, 3.0, 40.0}) {
      const long double reference =
          -std::expm1l(static_cast<long double>(n) * std::log1pl(-static_cast<long double>(ratio)));
      const double relative = static_cast<double>((SpbrAlpha(n, ratio) - reference) / reference);
      EXPECT_LT(std::abs(relative), 1e-12) << n << " " << ratio;
    }
  }
  // n/L = 3 has the exact polynomial 1 - (1 - x)^3 = 3x - 3x^2 + x^3.
  const double x = 1e-12;
  EXPECT_NEAR(SpbrAlpha(3.0, x) / (3 * x - 3 * x * x + x * x * x), 1.0, 1e-15);
  // The naive form, for contrast: it keeps only ~4 digits here, so the tests above can fail.
  EXPECT_GT(std::abs((1.0 - std::pow(1.0 - x, 3.0)) / (3 * x) - 1.0), 1e-6);
  const long double inverse = std::log1pl(-0.5L) / std::log1pl(-1e-12L);
  EXPECT_NEAR(SpbrPointsPerEnsemble(0.5, 1e-12) / static_cast<double>(inverse), 1.0, 1e-12);
}

// ---- Point-number adjustment ----

constexpr double kDensity = 1000.0;  // points per m^2 of the test plane
constexpr double kRadius = 0.1;      // density radius: S = pi r^2, ~31 points

// A uniform random plane of n points (10 x 10 m at kDensity for 100k) with colours and a scalar.
PointCloud Plane(size_t n, uint64_t seed) {
  PointCloud cloud;
  cloud.schema.colors = true;
  cloud.schema.scalars = {{"intensity", ScalarType::kFloat32}};
  cloud.SetSchema(cloud.schema);
  cloud.Resize(n);
  const double side = std::sqrt(n / kDensity);
  Rng rng(seed);
  for (size_t i = 0; i < n; ++i) {
    cloud.positions[i] = Eigen::Vector3d(rng.Uniform(0, side), rng.Uniform(0, side), 0.25);
    cloud.colors[i] = {static_cast<uint8_t>(i), static_cast<uint8_t>(i >> 8), 9};
    cloud.scalars[0].f32[i] = static_cast<float>(i);
  }
  return cloud;
}

// Options whose typical ratio r = n' / (kDensity S) is `ratio`: from n' = L ln(1-a)/ln(1-s/S),
// with S = s / kMaxPointAreaRatio (these pixels are coarser than the density disc).
OpacityOptions ForRatio(double alpha, int repeat_level, double ratio) {
  OpacityOptions o;
  o.alpha = alpha;
  o.spbr.repeat_level = repeat_level;
  o.density.radius = kRadius;
  const double k = kMaxPointAreaRatio;
  const double s = repeat_level * SpbrPointsPerEnsemble(alpha, k) * k / (kDensity * ratio);
  EXPECT_GT(s, k * M_PI * kRadius * kRadius) << "S is enlarged";
  o.image_size = 0;
  o.pixel_size = std::sqrt(s);
  return o;
}

double EffectiveArea(const OpacityOptions& o, double density_area) {
  return std::max(density_area, o.pixel_size * o.pixel_size / kMaxPointAreaRatio);
}

std::vector<int> Copies(const PointCloud& cloud) {
  const ScalarField* field = cloud.FindScalar(kMultiplicityField);
  EXPECT_NE(field, nullptr);
  std::vector<int> m;
  for (size_t i = 0; field && i < cloud.size(); ++i) m.push_back(static_cast<int>(field->Get(i)));
  return m;
}

// Sum over points of min(r_i, L), from the densities, independently of AdjustOpacity's code.
double ExpectedCopies(const OpacityOptions& o, const PointCloud& cloud) {
  const DensityResult density = EstimateSurfaceDensity(o.density, cloud);
  const double area = EffectiveArea(o, density.area);
  const double s_over_S = o.pixel_size * o.pixel_size / area;
  const double needed = o.spbr.repeat_level * SpbrPointsPerEnsemble(o.alpha, s_over_S);
  double sum = 0;
  for (double rho : density.density) {
    sum += std::min(needed / (rho * area), 1.0 * o.spbr.repeat_level);
  }
  return sum;
}

TEST(SamplingModuleOptions, DefaultsPassCheck) {
  EXPECT_NO_THROW(DensityOptions().Check());
  EXPECT_NO_THROW(OpacityOptions().Check());
  // SurfaceSampleOptions has no valid default: a count or a density must be given (its own test
  // checks that the defaults throw).
  SurfaceSampleOptions sample;
  sample.count = 1;
  EXPECT_NO_THROW(sample.Check());
}

TEST(OpacityOptions, DefaultsPassAndBadValuesNameTheField) {
  EXPECT_NO_THROW(OpacityOptions().Check());
  auto message = [](const OpacityOptions& o) {
    try {
      o.Check();
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no throw");
  };
  OpacityOptions o;
  o.alpha = 1.5;
  EXPECT_EQ(message(o), "OpacityOptions::alpha = 1.5; must be in [0, 1]");
  o = {};
  o.spbr.repeat_level = 0;
  EXPECT_EQ(message(o), "SpbrSettings::repeat_level = 0; must be in [1, 100000]");
  o = {};
  o.pixel_size = 0.01;
  EXPECT_EQ(message(o),
            "OpacityOptions::pixel_size = 0.01 and image_size = 1024; exactly one "
            "must be > 0 (the other 0)");
  o.image_size = 0;
  EXPECT_EQ(message(o), "no throw");
  o.pixel_size = 0;
  EXPECT_NE(message(o).find("exactly one"), std::string::npos);
  o = {};
  o.density.target_neighbours = 0;
  EXPECT_NE(message(o).find("DensityOptions::target_neighbours = 0"), std::string::npos);
}

TEST(AdjustOpacity, ReplicationMatchesTheRatiosInExpectation) {
  const PointCloud cloud = Plane(100000, 1);
  const OpacityOptions o = ForRatio(0.5, 10, 1.7);
  const OpacityResult r = AdjustOpacity(o, cloud);
  const OpacitySummary& s = r.summary;
  EXPECT_NEAR(s.ratio_median, 1.7, 0.3);
  EXPECT_NEAR(s.expected_copies / ExpectedCopies(o, cloud), 1.0, 1e-9);
  EXPECT_NEAR(static_cast<double>(s.total_copies) / s.expected_copies, 1.0, 0.01);
  EXPECT_GT(s.replicated, cloud.size() / 3);
  EXPECT_EQ(s.points_in, cloud.size());
  EXPECT_EQ(s.points_out + s.removed, s.points_in);
  EXPECT_NEAR(s.predicted_alpha, 0.5, 1e-9) << "the median point is not capped";
  EXPECT_NEAR(s.point_area_ratio, kMaxPointAreaRatio, 1e-12);
  EXPECT_NEAR(s.area, o.pixel_size * o.pixel_size / kMaxPointAreaRatio, 1e-12);
  const std::vector<int> m = Copies(r.cloud);
  ASSERT_EQ(m.size(), r.cloud.size());
  uint64_t total = 0;
  for (int c : m) {
    ASSERT_GE(c, 1);
    ASSERT_LE(c, o.spbr.repeat_level);
    total += c;
  }
  EXPECT_EQ(total, s.total_copies);
}

TEST(AdjustOpacity, RemovalKeepsTheRatioOfPoints) {
  const PointCloud cloud = Plane(100000, 2);
  const OpacityOptions o = ForRatio(0.2, 10, 0.4);
  const OpacityResult r = AdjustOpacity(o, cloud);
  const OpacitySummary& s = r.summary;
  EXPECT_NEAR(s.ratio_median, 0.4, 0.1);
  EXPECT_NEAR(static_cast<double>(s.total_copies) / ExpectedCopies(o, cloud), 1.0, 0.01);
  EXPECT_GT(s.removed, cloud.size() / 2);
  EXPECT_LT(s.replicated, cloud.size() / 100) << "only the sparsest spots get copies";
  EXPECT_EQ(s.capped, 0u);
  EXPECT_NEAR(s.predicted_alpha, 0.2, 1e-9);
}

TEST(AdjustOpacity, KeepsOrderAndAttributes) {
  const PointCloud cloud = Plane(20000, 3);
  const OpacityResult r = AdjustOpacity(ForRatio(0.2, 10, 0.5), cloud);
  ASSERT_TRUE(r.cloud.schema.colors);
  ASSERT_EQ(r.cloud.schema.scalars.size(), 2u);
  EXPECT_EQ(r.cloud.schema.scalars[1].name, "spbr_multiplicity");
  const ScalarField* index = r.cloud.FindScalar("intensity");
  ASSERT_NE(index, nullptr);
  for (size_t j = 0; j < r.cloud.size(); ++j) {
    const size_t i = static_cast<size_t>(index->Get(j));
    ASSERT_TRUE(j == 0 || i > static_cast<size_t>(index->Get(j - 1))) << "input order";
    ASSERT_EQ(r.cloud.positions[j], cloud.positions[i]);
    ASSERT_EQ(r.cloud.colors[j], cloud.colors[i]);
  }
}

TEST(AdjustOpacity, CopiesAreCappedAtTheRepeatLevel) {
  const PointCloud cloud = Plane(20000, 4);
  const OpacityOptions o = ForRatio(0.9, 4, 3.0);
  const OpacityResult r = AdjustOpacity(o, cloud);
  EXPECT_GT(r.summary.capped, 0u);
  for (int c : Copies(r.cloud)) ASSERT_LE(c, 4);
  EXPECT_NE(r.summary.message.find("capped"), std::string::npos) << r.summary.message;
}

TEST(AdjustOpacity, SeededAndIndependentOfThreads) {
  const PointCloud cloud = Plane(30000, 5);
  OpacityOptions o = ForRatio(0.5, 10, 1.3);
  o.density.radius = 0;  // the automatic radius's sample is seeded too
  OpacityResult one, two;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = AdjustOpacity(o, cloud);
  }
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 2);
    two = AdjustOpacity(o, cloud);
  }
  EXPECT_EQ(one.cloud.positions, two.cloud.positions);
  EXPECT_EQ(Copies(one.cloud), Copies(two.cloud));
  EXPECT_EQ(one.summary.total_copies, two.summary.total_copies);
  o.spbr.seed = 2;
  const OpacityResult other = AdjustOpacity(o, cloud);
  EXPECT_NE(Copies(other.cloud), Copies(one.cloud));
  EXPECT_NEAR(static_cast<double>(other.summary.total_copies) / one.summary.total_copies, 1.0,
              0.01);
}

TEST(AdjustOpacity, AlphaZeroRemovesEverythingAndAlphaOneCapsEverything) {
  const PointCloud cloud = Plane(5000, 6);
  OpacityOptions o = ForRatio(0.5, 8, 1.0);
  o.alpha = 0;
  OpacityResult r = AdjustOpacity(o, cloud);
  EXPECT_TRUE(r.cloud.empty());
  EXPECT_NE(r.cloud.FindScalar(kMultiplicityField), nullptr) << "the schema is still complete";
  EXPECT_EQ(r.summary.removed, cloud.size());
  EXPECT_EQ(r.summary.total_copies, 0u);
  EXPECT_EQ(r.summary.predicted_alpha, 0.0);
  EXPECT_NE(r.summary.message.find("alpha = 0: every point removed"), std::string::npos);
  o.alpha = 1;
  r = AdjustOpacity(o, cloud);
  EXPECT_EQ(r.summary.capped, cloud.size());
  EXPECT_EQ(r.summary.total_copies, 8u * cloud.size());
  for (int c : Copies(r.cloud)) ASSERT_EQ(c, 8);
  EXPECT_LT(r.summary.predicted_alpha, 1.0);
  EXPECT_EQ(r.summary.ratio_min, kInf);
}

TEST(AdjustOpacity, EmptySingleAndImageSize) {
  OpacityResult r = AdjustOpacity(OpacityOptions(), PointCloud());
  EXPECT_TRUE(r.cloud.empty());
  EXPECT_EQ(r.summary.points_in, 0u);
  PointCloud one;
  one.positions = {Eigen::Vector3d(1, 2, 3)};
  r = AdjustOpacity(OpacityOptions(), one);
  ASSERT_EQ(r.cloud.size(), 1u) << "an isolated point is kept at the cap";
  EXPECT_EQ(Copies(r.cloud)[0], 100);
  // image_size: s_side = the largest extent / N.
  const PointCloud cloud = Plane(10000, 7);
  OpacityOptions o;
  o.image_size = 500;
  r = AdjustOpacity(o, cloud);
  EXPECT_NEAR(r.summary.pixel_size, cloud.LocalBounds().Extent().maxCoeff() / 500, 1e-15);
}

TEST(AdjustOpacity, CoarsePixelsEnlargeTheArea) {
  const PointCloud cloud = Plane(10000, 8);
  OpacityOptions o;
  o.density.radius = kRadius;
  o.image_size = 0;
  o.pixel_size = 0.2;  // s = 0.04 m^2 > pi r^2 / 100
  const OpacityResult r = AdjustOpacity(o, cloud);
  EXPECT_NEAR(r.summary.point_area_ratio, kMaxPointAreaRatio, 1e-12);
  EXPECT_NEAR(r.summary.area, 0.04 / kMaxPointAreaRatio, 1e-12);
  EXPECT_NE(r.summary.message.find("S enlarged"), std::string::npos) << r.summary.message;
  EXPECT_GT(r.cloud.size(), 0u);
}

TEST(AdjustOpacity, ReadjustingKeepsTheCopyCount) {
  // The output of one adjustment, adjusted again with the same options, is already at target:
  // its multiplicities count as points, so the copy total stays (in expectation).
  const PointCloud cloud = Plane(50000, 9);
  const OpacityOptions o = ForRatio(0.5, 10, 1.6);
  const OpacityResult first = AdjustOpacity(o, cloud);
  const OpacityResult second = AdjustOpacity(o, first.cloud);
  EXPECT_NEAR(second.summary.ratio_median, 1.0, 0.1);
  EXPECT_NEAR(static_cast<double>(second.summary.total_copies) / first.summary.total_copies, 1.0,
              0.05);
  PointCloud bad = first.cloud;
  bad.FindScalar(kMultiplicityField)->Set(0, -2.0);
  EXPECT_THROW(AdjustOpacity(o, bad), InputError);
}

}  // namespace
}  // namespace candi::sampling

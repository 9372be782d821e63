#include "reconstruction/photogrammetry/georef/similarity_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "core/rng.h"

namespace candi::photogrammetry {
namespace {

using V = Eigen::Vector3d;

Sim3 TrueTransform(const V& translation) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.7, V(0.2, -0.3, 1.0).normalized()));
  return Sim3(0.8, q, translation);
}

// A site of n targets: spread over ~100 m with ~20 m of height, in model coordinates.
std::vector<V> Layout(int n, uint64_t seed, double height = 20) {
  Rng rng(seed);
  std::vector<V> p;
  for (int i = 0; i < n; ++i) {
    p.emplace_back(rng.Uniform(-60, 60), rng.Uniform(-60, 60), rng.Uniform(0, height));
  }
  return p;
}

std::vector<V> Apply(const Sim3& t, const std::vector<V>& p, double noise, uint64_t seed) {
  Rng rng(seed);
  std::vector<V> out;
  for (const V& x : p) out.push_back(t * x + noise * V(rng.Normal(), rng.Normal(), rng.Normal()));
  return out;
}

double AngleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return a.angularDistance(b);
}

TEST(SimilarityFitOptions, DefaultsPassAndBadValuesNameTheField) {
  SimilarityFitOptions o;
  EXPECT_NO_THROW(o.Check());
  o.loss_scale = 0;
  try {
    o.Check();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("loss_scale = 0"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ParseRobustLoss("cauchy"), RobustLoss::kCauchy);
  EXPECT_THROW(ParseRobustLoss("l1"), std::invalid_argument);
}

TEST(FitSimilarity, RecoversAnExactTransform) {
  const Sim3 truth = TrueTransform(V(100, -50, 7));
  const std::vector<V> x = Layout(6, 1);
  const SimilarityFitResult r = FitSimilarity({}, x, Apply(truth, x, 0, 0));
  EXPECT_TRUE(r.converged) << r.solver_message;
  EXPECT_NEAR(r.target_from_source.scale, 0.8, 1e-12);
  EXPECT_LT(AngleBetween(r.target_from_source.rotation, truth.rotation), 1e-12);
  EXPECT_LT((r.target_from_source.translation - truth.translation).norm(), 1e-9);
  EXPECT_LT(r.rms, 1e-9);
  EXPECT_EQ(r.inliers, 6);
  EXPECT_FALSE(r.collinear);
  EXPECT_FALSE(r.coplanar);
  EXPECT_TRUE(r.warnings.empty());
}

TEST(FitSimilarity, FlagsOneBlunderAndRecoversFromNoisyTargets) {
  const Sim3 truth = TrueTransform(V(12, 30, -4));
  const std::vector<V> x = Layout(12, 2);
  const double noise = 0.003;  // m per axis
  std::vector<V> y = Apply(truth, x, noise, 3);
  y[5] += V(0.4, -0.3, 0.2);  // a mistyped coordinate
  for (RobustLoss loss : {RobustLoss::kHuber, RobustLoss::kCauchy}) {
    SimilarityFitOptions o;
    o.loss = loss;
    const SimilarityFitResult r = FitSimilarity(o, x, y, std::vector<double>(12, 0.005));
    SCOPED_TRACE(RobustLossName(loss));
    EXPECT_TRUE(r.converged) << r.solver_message;
    for (size_t i = 0; i < 12; ++i) EXPECT_EQ(r.outlier[i], i == 5) << i;
    EXPECT_EQ(r.inliers, 11);
    EXPECT_GT(r.residuals[5].norm(), 0.4);
    EXPECT_NEAR(r.target_from_source.scale, 0.8, 1e-4);
    // Check points (not in the fit) land within the noise level of their truth.
    const std::vector<V> check = Layout(20, 4);
    double sum = 0;
    for (const V& c : check) sum += (r.target_from_source * c - truth * c).squaredNorm();
    EXPECT_LT(std::sqrt(sum / 20), 2 * noise);
    EXPECT_LT(r.rms, 3 * noise * std::sqrt(3.0));
    EXPECT_GT(r.robust_sigma, 0.3 * noise);
    EXPECT_LT(r.robust_sigma, 2 * noise);
  }
}

TEST(FitSimilarity, SurveyCoordinatesKeepMillimetres) {
  // UTM 49S at Borobudur: E ~ 416000, N ~ 9168000; the model is small and rotated.
  const Sim3 truth = TrueTransform(V(416000.123, 9168000.456, 265.789));
  const std::vector<V> x = Layout(10, 5);
  const double noise = 0.001;
  const std::vector<V> y = Apply(truth, x, noise, 6);
  const SimilarityFitResult r = FitSimilarity({}, x, y, std::vector<double>(10, 0.002));
  EXPECT_TRUE(r.converged) << r.solver_message;
  EXPECT_EQ(r.inliers, 10);
  EXPECT_LT(r.rms, 3 * noise);
  for (const V& d : r.residuals) EXPECT_LT(d.norm(), 5 * noise);
  for (const V& c : Layout(5, 7)) {
    EXPECT_LT((r.target_from_source * c - truth * c).norm(), 0.002);
  }
  // Noise-free: exact to well below a millimetre despite the 10^7 m coordinates.
  const SimilarityFitResult exact = FitSimilarity({}, x, Apply(truth, x, 0, 0));
  for (const V& d : exact.residuals) EXPECT_LT(d.norm(), 1e-6);
}

TEST(FitSimilarity, RigidFitKeepsUnitScale) {
  const Sim3 truth(1.0, TrueTransform(V::Zero()).rotation, V(5, 6, 7));
  const std::vector<V> x = Layout(5, 8);
  SimilarityFitOptions o;
  o.estimate_scale = false;
  const SimilarityFitResult r = FitSimilarity(o, x, Apply(truth, x, 0.001, 9));
  EXPECT_EQ(r.target_from_source.scale, 1.0);
  EXPECT_LT((r.target_from_source.translation - truth.translation).norm(), 0.005);
}

TEST(FitSimilarity, ReportsCollinearTargets) {
  std::vector<V> x;
  Rng rng(10);
  for (int i = 0; i < 6; ++i) x.push_back(V(10.0 * i, 2.0 * i, 0.5 * i) + 0.01 * V(rng.Normal(), rng.Normal(), 0));
  const SimilarityFitResult r = FitSimilarity({}, x, Apply(TrueTransform(V(1, 2, 3)), x, 0, 0));
  EXPECT_TRUE(r.collinear);
  EXPECT_LT(r.collinearity, 0.01);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings[0].find("collinear (s2/s1 = "), std::string::npos) << r.warnings[0];
}

TEST(FitSimilarity, ReportsCoplanarTargets) {
  const std::vector<V> x = Layout(8, 11, 0.5);  // 120 m across, 0.5 m of relief
  const SimilarityFitResult r = FitSimilarity({}, x, Apply(TrueTransform(V(1, 2, 3)), x, 0.001, 12));
  EXPECT_FALSE(r.collinear);
  EXPECT_TRUE(r.coplanar);
  EXPECT_LT(r.planarity, 0.05);
  EXPECT_GT(r.planarity, 0.0);
  ASSERT_FALSE(r.warnings.empty());
  EXPECT_NE(r.warnings[0].find("coplanar"), std::string::npos) << r.warnings[0];
  EXPECT_NE(r.warnings[0].find("vertical"), std::string::npos) << r.warnings[0];
}

TEST(FitSimilarity, RejectsFewerThanThreeAndCoincidentPoints) {
  const std::vector<V> two = {V(0, 0, 0), V(1, 0, 0)};
  EXPECT_THROW(FitSimilarity({}, two, two), std::invalid_argument);
  const std::vector<V> same(4, V(3, 3, 3));
  EXPECT_THROW(FitSimilarity({}, same, same), std::invalid_argument);
  std::vector<V> nan = Layout(4, 1);
  nan[2].x() = std::nan("");
  EXPECT_THROW(FitSimilarity({}, nan, Layout(4, 1)), std::invalid_argument);
  EXPECT_THROW(FitSimilarity({}, Layout(4, 1), Layout(4, 1), {1, 1, 0, 1}), std::invalid_argument);
}

TEST(FitSimilarity, AbsoluteThresholdAndFlagOnlyMode) {
  const Sim3 truth = TrueTransform(V(0, 0, 0));
  const std::vector<V> x = Layout(10, 13);
  std::vector<V> y = Apply(truth, x, 0.002, 14);
  y[0] += V(0, 0, 0.05);
  SimilarityFitOptions o;
  o.outlier_threshold = 0.5;  // m: a 5 cm error is tolerated
  EXPECT_EQ(FitSimilarity(o, x, y).inliers, 10);
  o.outlier_threshold = 0;
  o.remove_outliers = false;
  const SimilarityFitResult r = FitSimilarity(o, x, y, std::vector<double>(10, 0.002));
  EXPECT_TRUE(r.outlier[0]);
  EXPECT_EQ(r.inliers, 10);  // flagged but kept
}

TEST(FitSimilarity, NonConvergenceIsAResult) {
  const std::vector<V> x = Layout(10, 15);
  std::vector<V> y = Apply(TrueTransform(V(3, 2, 1)), x, 0.01, 16);
  y[1] += V(5, 5, 5);
  SimilarityFitOptions o;
  o.max_iterations = 1;
  o.loss = RobustLoss::kCauchy;
  o.loss_scale = 0.001;
  o.remove_outliers = false;
  const SimilarityFitResult r = FitSimilarity(o, x, y);
  EXPECT_FALSE(r.converged);
  EXPECT_FALSE(r.solver_message.empty());
  EXPECT_NE(r.warnings.back().find("did not converge"), std::string::npos);
}

}  // namespace
}  // namespace candi::photogrammetry

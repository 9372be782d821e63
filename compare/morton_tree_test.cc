#include "compare/morton_tree.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "compare/deviation_internal.h"
#include "core/rng.h"

namespace candi::compare::internal {
namespace {

// Points on a wavy surface in Morton order.
std::vector<Eigen::Vector3d> SurfacePoints(size_t n, uint64_t seed) {
  Rng rng(seed);
  std::vector<Eigen::Vector3d> raw;
  for (size_t i = 0; i < n; ++i) {
    const double x = rng.Uniform(0, 10), y = rng.Uniform(0, 10);
    raw.emplace_back(x, y, 0.3 * std::sin(x) + 0.001 * rng.Normal());
  }
  std::vector<Eigen::Vector3d> sorted;
  for (uint32_t i : MortonOrder(raw)) sorted.push_back(raw[i]);
  return sorted;
}

TEST(MortonTreeTest, AnswersAsABruteForceSearch) {
  const std::vector<Eigen::Vector3d> pts = SurfacePoints(20000, 1);  // 2048 leaves of 10 (the last ones fewer)
  const MortonTree tree(pts);
  Rng rng(2);
  int64_t hint = -1;
  for (int t = 0; t < 300; ++t) {
    const Eigen::Vector3d q(rng.Uniform(-1, 11), rng.Uniform(-1, 11), rng.Uniform(-1, 1));
    std::vector<std::pair<double, uint32_t>> all;
    for (uint32_t i = 0; i < pts.size(); ++i) all.emplace_back((pts[i] - q).squaredNorm(), i);
    std::sort(all.begin(), all.end());
    // Nearest, without and with a hint (the previous query's answer).
    EXPECT_EQ((pts[static_cast<size_t>(tree.Nearest(q, -1))] - q).squaredNorm(), all[0].first);
    hint = tree.Nearest(q, hint);
    EXPECT_EQ((pts[static_cast<size_t>(hint)] - q).squaredNorm(), all[0].first);
    // k nearest, sorted.
    uint32_t index[12];
    double dist_sq[12];
    ASSERT_EQ(tree.Knn(q, 12, index, dist_sq), 12u);
    for (int j = 0; j < 12; ++j) {
      EXPECT_EQ(dist_sq[j], all[static_cast<size_t>(j)].first) << j;
      EXPECT_EQ((pts[index[j]] - q).squaredNorm(), dist_sq[j]);
    }
    // Every point within a radius, once.
    const double radius = 0.3;
    std::vector<uint32_t> within;
    tree.ForEachWithin(q, radius, [&](uint32_t i, double) { within.push_back(i); });
    std::sort(within.begin(), within.end());
    EXPECT_EQ(std::adjacent_find(within.begin(), within.end()), within.end());
    size_t expected = 0;
    for (const auto& [d, i] : all) expected += d <= radius * radius ? 1 : 0;
    EXPECT_EQ(within.size(), expected);
  }
  // Fewer points than k.
  const std::vector<Eigen::Vector3d> few = {{0, 0, 0}, {1, 0, 0}};
  const MortonTree small(few);
  uint32_t index[5];
  double dist_sq[5];
  EXPECT_EQ(small.Knn({0.2, 0, 0}, 5, index, dist_sq), 2u);
  EXPECT_EQ(index[0], 0u);
  EXPECT_EQ(index[1], 1u);
  // One point, none, and coincident points (every leaf's box a point).
  const std::vector<Eigen::Vector3d> one = {{416000.25, 9168000.5, 200.125}};
  EXPECT_EQ(MortonTree(one).Nearest({0, 0, 0}, -1), 0);
  const std::vector<Eigen::Vector3d> none;
  EXPECT_EQ(MortonTree(none).Nearest({0, 0, 0}, -1), -1);
  EXPECT_EQ(MortonTree(none).Knn({0, 0, 0}, 3, index, dist_sq), 0u);
  const std::vector<Eigen::Vector3d> same(1000, Eigen::Vector3d(1, 2, 3));
  const MortonTree coincident(same);
  EXPECT_EQ(coincident.Knn({1, 2, 3.5}, 5, index, dist_sq), 5u);
  EXPECT_EQ(dist_sq[4], 0.25);
  size_t within = 0;
  coincident.ForEachWithin({1, 2, 3.5}, 0.5, [&](uint32_t, double) { ++within; });  // on the sphere: in
  EXPECT_EQ(within, 1000u);
}

}  // namespace
}  // namespace candi::compare::internal

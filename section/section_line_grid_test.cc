#include "section/section_line_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <vector>

namespace candi::section::lines_internal {
namespace {

TEST(CellTable, KeepsTheFirstValueOfAKeyThroughGrowth) {
  CellTable table;
  EXPECT_EQ(table.Find(7), kNone);  // empty
  constexpr uint64_t kStride = 40503;
  for (uint32_t i = 0; i < 1000; ++i) EXPECT_EQ(table.FindOrInsert(i * kStride, i), i);
  for (uint32_t i = 0; i < 1000; ++i) EXPECT_EQ(table.FindOrInsert(i * kStride, 5000), i);
  EXPECT_EQ(table.Find(999 * kStride), 999u);
  EXPECT_EQ(table.Find(1), kNone);
  std::vector<uint32_t> plus_one(1000);
  for (uint32_t i = 0; i < 1000; ++i) plus_one[i] = i + 1;
  table.Renumber(plus_one);
  EXPECT_EQ(table.Find(0), 1u);
  EXPECT_EQ(table.Find(999 * kStride), 1000u);
}

TEST(BuildBuckets, GroupsItemsByCellInKeyOrderAndFindsNeighbours) {
  const std::vector<Eigen::Vector2d> p = {{2.5, 0.5}, {0.5, 0.5}, {2.6, 0.4}, {-5, -5}, {0.1, 0.9}};
  const Buckets b = BuildBuckets(p.size(), 1.0, [&](size_t i, Eigen::Vector2d* q) {
    *q = p[i];
    return i != 3;  // skipped
  });
  EXPECT_EQ(b.items, (std::vector<uint32_t>{1, 4, 0, 2}));  // cell (0, 0), then (2, 0)
  EXPECT_EQ(b.start, (std::vector<uint32_t>{0, 2, 4}));
  auto near = [&](const Eigen::Vector2d& at) {
    std::vector<uint32_t> items;
    b.ForEachNear(at, [&](uint32_t slot) { items.push_back(b.items[slot]); });
    std::sort(items.begin(), items.end());
    return items;
  };
  EXPECT_EQ(near({1.5, 0.5}), (std::vector<uint32_t>{0, 1, 2, 4}));
  EXPECT_EQ(near({3.5, 1.5}), (std::vector<uint32_t>{0, 2}));
  EXPECT_TRUE(near({4.5, 0.5}).empty());
}

TEST(BuildPointGrid, SkipsNonFinitePointsAndIgnoresTheInputOrder) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<Eigen::Vector2d> input = {
      {10.2, 5.1}, {nan, 1.0}, {11.7, 5.3}, {10.2, 5.05}, {10.9, 7.5}};
  const Eigen::Vector2d origin(10, 5);
  const PointGrid grid = BuildPointGrid(input, origin, 1.0);
  // Cells (0, 0), (0, 2), (1, 0); within a cell by (u, v).
  const std::vector<Eigen::Vector2d> expected = {
      input[3] - origin, input[0] - origin, input[4] - origin, input[2] - origin};
  EXPECT_EQ(grid.points, expected);
  EXPECT_EQ(grid.buckets.start, (std::vector<uint32_t>{0, 2, 3, 4}));
  std::reverse(input.begin(), input.end());
  EXPECT_EQ(BuildPointGrid(input, origin, 1.0).points, expected);
}

}  // namespace
}  // namespace candi::section::lines_internal

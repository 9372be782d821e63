#include "section/section_line_grid.h"

namespace candi::section::lines_internal {

PointGrid BuildPointGrid(const std::vector<Eigen::Vector2d>& input, const Eigen::Vector2d& origin,
                         double cell) {
  PointGrid grid;
  grid.buckets = BuildBuckets(input.size(), cell, [&](size_t i, Eigen::Vector2d* p) {
    if (!input[i].allFinite()) return false;
    *p = input[i] - origin;
    return true;
  });
  grid.points.resize(grid.buckets.items.size());
  for (size_t k = 0; k < grid.points.size(); ++k) {
    grid.points[k] = input[grid.buckets.items[k]] - origin;
  }
  auto less = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() != b.x() ? a.x() < b.x() : a.y() < b.y();
  };
  const std::vector<uint32_t>& start = grid.buckets.start;
  for (size_t c = 0; c + 1 < start.size(); ++c) {
    std::sort(grid.points.begin() + start[c], grid.points.begin() + start[c + 1], less);
  }
  grid.buckets.items = {};  // input indices: no longer needed
  return grid;
}

}  // namespace candi::section::lines_internal

// A 2-D polyline: the lines of a drawing (a CAD section, a section cut through points), in
// drawing coordinates (metres, x horizontal, y up).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace candi {

struct Polyline2 {
  std::vector<Eigen::Vector2d> points;  // drawing coordinates, metres
  bool closed = false;                  // the last point joins the first
};

// The distance from `p` to the open polyline through `points` (its nearest segment; 1e300 for
// fewer than two points). Thread-safe.
double DistanceToPolyline(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& points);

}  // namespace candi

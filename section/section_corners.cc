#include "section/section_corners.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "core/check.h"

namespace candi::section {

void SectionCornerOptions::Check() const {
  CANDI_CHECK_OPTION_IN(min_turn_deg, 0, 90);
  CANDI_CHECK_OPTION_IN(window, 1, 20);
  CANDI_CHECK_OPTION(gain > 0 && gain <= 1, gain, "in (0, 1]");
  CANDI_CHECK_OPTION_GE(min_side_points, 2);
}

namespace {

// Points bucketed in square cells.
class Grid {
 public:
  Grid(const std::vector<Eigen::Vector2d>& points, double cell) : points_(points), cell_(cell) {
    for (size_t i = 0; i < points.size(); ++i) {
      if (points[i].allFinite()) cells_[Key(Cell(points[i].x()), Cell(points[i].y()))].push_back(static_cast<uint32_t>(i));
    }
  }
  template <typename F>
  void Near(const Eigen::Vector2d& c, double radius, F f) const {
    const int64_t x0 = Cell(c.x() - radius), x1 = Cell(c.x() + radius);
    const int64_t y0 = Cell(c.y() - radius), y1 = Cell(c.y() + radius);
    for (int64_t x = x0; x <= x1; ++x) {
      for (int64_t y = y0; y <= y1; ++y) {
        const auto it = cells_.find(Key(x, y));
        if (it == cells_.end()) continue;
        for (uint32_t i : it->second) {
          if ((points_[i] - c).squaredNorm() <= radius * radius) f(i);
        }
      }
    }
  }

 private:
  int64_t Cell(double v) const { return static_cast<int64_t>(std::floor(v / cell_)); }
  static uint64_t Key(int64_t x, int64_t y) {
    return static_cast<uint64_t>(x + (int64_t{1} << 31)) << 32 ^ static_cast<uint64_t>(y + (int64_t{1} << 31));
  }
  const std::vector<Eigen::Vector2d>& points_;
  double cell_;
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells_;
};

// Running sums of points, for total least squares line fits of any run in O(1).
struct Sums {
  double n = 0, x = 0, y = 0, xx = 0, xy = 0, yy = 0;
  void Add(const Eigen::Vector2d& p) { n += 1, x += p.x(), y += p.y(), xx += p.x() * p.x(), xy += p.x() * p.y(), yy += p.y() * p.y(); }
  Sums Minus(const Sums& o) const { return {n - o.n, x - o.x, y - o.y, xx - o.xx, xy - o.xy, yy - o.yy}; }
};

struct Line {
  Eigen::Vector2d centre = Eigen::Vector2d::Zero(), direction = Eigen::Vector2d::UnitX();
  double sse = 0;  // sum of squared distances of the points to the line
};

Line Fit(const Sums& s) {
  Line l;
  l.centre = Eigen::Vector2d(s.x, s.y) / s.n;
  Eigen::Matrix2d c;
  c(0, 0) = s.xx / s.n - l.centre.x() * l.centre.x();
  c(0, 1) = c(1, 0) = s.xy / s.n - l.centre.x() * l.centre.y();
  c(1, 1) = s.yy / s.n - l.centre.y() * l.centre.y();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> e(c);
  l.direction = e.eigenvectors().col(1);
  l.sse = std::max(0.0, e.eigenvalues()(0)) * s.n;
  return l;
}

// The closest point of segment [a, b] to p: its parameter in [0, 1] and distance.
double Project(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double* distance) {
  const Eigen::Vector2d d = b - a;
  const double t = d.squaredNorm() > 0 ? std::clamp((p - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
  *distance = (p - (a + t * d)).norm();
  return t;
}

std::vector<double> ArcLengths(const std::vector<Eigen::Vector2d>& v) {
  std::vector<double> s(v.size(), 0.0);
  for (size_t k = 1; k < v.size(); ++k) s[k] = s[k - 1] + (v[k] - v[k - 1]).norm();
  return s;
}

double TurnDeg(const std::vector<Eigen::Vector2d>& v, size_t i) {
  const Eigen::Vector2d a = v[i] - v[i - 1], b = v[i + 1] - v[i];
  if (a.norm() == 0 || b.norm() == 0) return 0;
  return std::acos(std::clamp(a.dot(b) / (a.norm() * b.norm()), -1.0, 1.0)) * 180 / M_PI;
}

// Tries a corner at vertex i of line v; on success replaces the vertices near it and returns true.
bool TryCorner(const SectionCornerOptions& o, const Grid& grid, const std::vector<Eigen::Vector2d>& points,
               double spacing, size_t i, std::vector<Eigen::Vector2d>* v) {
  const std::vector<double> s = ArcLengths(*v);
  const double w = o.window * spacing;
  // The points near the vertex that belong to this part of the line: position along it, residual.
  std::vector<std::pair<double, uint32_t>> along;
  double poly_sse = 0;
  grid.Near((*v)[i], w + spacing, [&](uint32_t k) {
    double best = 1e300, at = 0;
    for (size_t j = 0; j + 1 < v->size(); ++j) {
      if (s[j + 1] < s[i] - w - spacing || s[j] > s[i] + w + spacing) continue;
      double d;
      const double t = Project(points[k], (*v)[j], (*v)[j + 1], &d);
      if (d < best) best = d, at = s[j] + t * (s[j + 1] - s[j]);
    }
    if (best > 0.5 * spacing || std::abs(at - s[i]) > w) return;
    along.push_back({at, k});
    poly_sse += best * best;
  });
  const size_t m = along.size();
  if (m < 2 * o.min_side_points) return false;
  std::sort(along.begin(), along.end());
  std::vector<Sums> prefix(m + 1);
  for (size_t k = 0; k < m; ++k) {
    prefix[k + 1] = prefix[k];
    prefix[k + 1].Add(points[along[k].second]);
  }
  // The best break within a spacing of the vertex.
  double best_sse = 1e300;
  size_t best_b = 0;
  Line first, second;
  for (size_t b = o.min_side_points; b + o.min_side_points <= m; ++b) {
    if (std::abs(along[b].first - s[i]) > spacing) continue;
    const Line l1 = Fit(prefix[b]), l2 = Fit(prefix[m].Minus(prefix[b]));
    if (l1.sse + l2.sse < best_sse) best_sse = l1.sse + l2.sse, best_b = b, first = l1, second = l2;
  }
  if (best_b == 0) return false;
  if (!(best_sse < o.gain * o.gain * poly_sse)) return false;  // RMS ratio below gain
  const double cross = first.direction.x() * second.direction.y() - first.direction.y() * second.direction.x();
  if (std::asin(std::min(1.0, std::abs(cross))) * 180 / M_PI < o.min_turn_deg) return false;
  // Intersection: first.centre + a d1 = second.centre + b d2.
  const Eigen::Vector2d r = second.centre - first.centre;
  const double a = (r.x() * second.direction.y() - r.y() * second.direction.x()) / cross;
  const Eigen::Vector2d corner = first.centre + a * first.direction;
  if (!corner.allFinite() || (corner - (*v)[i]).norm() > 1.5 * spacing) return false;
  // The vertices within 0.75 spacing of the corner (along the line) give way to it.
  const double at = 0.5 * (along[best_b - 1].first + along[best_b].first);
  std::vector<Eigen::Vector2d> out;
  bool placed = false;
  for (size_t k = 0; k < v->size(); ++k) {
    if (!placed && s[k] > at) out.push_back(corner), placed = true;
    if (std::abs(s[k] - at) < 0.75 * spacing && k > 0 && k + 1 < v->size()) continue;
    out.push_back((*v)[k]);
  }
  if (!placed) out.push_back(corner);
  *v = std::move(out);
  return true;
}

}  // namespace

SectionCornerSummary RefineSectionCorners(const SectionCornerOptions& o, const std::vector<Eigen::Vector2d>& points,
                                          double spacing, std::vector<Polyline2>* lines) {
  o.Check();
  SectionCornerSummary summary;
  if (!(spacing > 0) || points.empty()) return summary;
  const Grid grid(points, spacing);
  for (Polyline2& line : *lines) {
    std::vector<Eigen::Vector2d>& v = line.points;
    // Candidates by decreasing turn; a corner placed ends the tries within its window.
    std::vector<std::pair<double, size_t>> turns;
    // A corner concentrates the turning in a vertex or two; a smooth curve (however tight: a
    // column's circle) turns evenly, so its vertices turn no more than those two further on.
    for (size_t i = 1; i + 1 < v.size(); ++i) {
      const double t = TurnDeg(v, i);
      const double before = i >= 3 ? TurnDeg(v, i - 2) : 0, after = i + 3 < v.size() ? TurnDeg(v, i + 2) : 0;
      if (t >= o.min_turn_deg && t > 2 * std::max(before, after)) turns.push_back({t, i});
    }
    std::sort(turns.begin(), turns.end(), [](const auto& a, const auto& b) { return a.first > b.first || (a.first == b.first && a.second < b.second); });
    std::vector<Eigen::Vector2d> done;  // corners placed on this line
    for (const auto& [turn, unused] : turns) {
      // The vertex may have moved: find the one that turns this much nearest its old place.
      size_t i = 0;
      for (size_t k = 1; k + 1 < v.size(); ++k) {
        if (std::abs(TurnDeg(v, k) - turn) < 1e-9) i = k;
      }
      if (i == 0) continue;
      bool near_done = false;
      for (const Eigen::Vector2d& c : done) near_done |= (c - v[i]).norm() < o.window * spacing;
      if (near_done) continue;
      if (TryCorner(o, grid, points, spacing, i, &v)) {
        ++summary.corners;
        done.push_back(v[std::min(i, v.size() - 1)]);
      }
    }
  }
  return summary;
}

}  // namespace candi::section

#include "mesh/profile.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/check.h"
#include "core/text_format.h"
#include "mesh/hermite.h"

namespace candi::mesh {

namespace {

double Extent(const std::vector<Eigen::Vector2d>& points) {
  Eigen::Vector2d lo = points.front(), hi = points.front();
  for (const Eigen::Vector2d& p : points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  return (hi - lo).maxCoeff();
}

// Inserts the arc-length midpoint of the path points[i0..i1] (unless it falls on a vertex) and
// returns its index.
size_t InsertRunMidpoint(std::vector<Eigen::Vector2d>* points, size_t i0, size_t i1) {
  std::vector<Eigen::Vector2d>& p = *points;
  double length = 0;
  for (size_t k = i0; k < i1; ++k) length += (p[k + 1] - p[k]).norm();
  double remaining = length / 2;
  for (size_t k = i0; k < i1; ++k) {
    const double step = (p[k + 1] - p[k]).norm();
    if (remaining <= 1e-12 * length) return k;
    if (remaining < step - 1e-12 * length) {
      const Eigen::Vector2d mid = p[k] + (p[k + 1] - p[k]) * (remaining / step);
      p.insert(p.begin() + static_cast<std::ptrdiff_t>(k + 1), mid);
      return k + 1;
    }
    remaining -= step;
  }
  return i1;
}

// The vertex of points[first..last] with the largest sign * y, ties broken as the header says.
// May insert a vertex (the midpoint of a tied run); returns the index of the split vertex.
size_t SplitIndex(std::vector<Eigen::Vector2d>* points, size_t first, size_t last, double sign,
                  double tolerance) {
  const std::vector<Eigen::Vector2d>& p = *points;
  double best = -std::numeric_limits<double>::infinity();
  for (size_t k = first; k <= last; ++k) best = std::max(best, sign * p[k].y());
  std::vector<size_t> tied;
  for (size_t k = first; k <= last; ++k) {
    if (sign * p[k].y() >= best - tolerance) tied.push_back(k);
  }
  if (tied.size() == 1) return tied[0];
  if (tied.back() - tied.front() + 1 == tied.size()) {
    return InsertRunMidpoint(points, tied.front(), tied.back());
  }
  double mean_x = 0;
  for (size_t k : tied) mean_x += p[k].x() / static_cast<double>(tied.size());
  size_t pick = tied[0];
  for (size_t k : tied) {
    const double dk = std::abs(p[k].x() - mean_x), dp = std::abs(p[pick].x() - mean_x);
    if (dk < dp || (dk == dp && p[k].x() < p[pick].x())) pick = k;
  }
  return pick;
}

double MeanX(const std::vector<Eigen::Vector2d>& side) {
  double sum = 0;
  for (const Eigen::Vector2d& p : side) sum += p.x();
  return sum / static_cast<double>(side.size());
}

// The two sides of `section` (drawing coordinates), each from the reference outward.
void SplitSides(const Polyline2& section, double tolerance, const SectionSource& source,
                std::vector<Eigen::Vector2d>* a, std::vector<Eigen::Vector2d>* b) {
  std::vector<Eigen::Vector2d> p = section.points;
  if (!section.closed) {
    const size_t r = SplitIndex(&p, 0, p.size() - 1, 1.0, tolerance);
    a->assign(p.rbegin() + static_cast<std::ptrdiff_t>(p.size() - 1 - r), p.rend());
    b->assign(p.begin() + static_cast<std::ptrdiff_t>(r), p.end());
    return;
  }
  // Closed: start at the lowest vertex so that the top's tied run cannot wrap around the start.
  const auto low = std::min_element(p.begin(), p.end(),
                                    [](const auto& u, const auto& v) { return u.y() < v.y(); });
  std::rotate(p.begin(), low, p.end());
  if (p.front().y() >= std::max_element(
                           p.begin(), p.end(),
                           [](const auto& u, const auto& v) {
                             return u.y() < v.y();
                           })->y() -
                           tolerance) {
    FailSection(source, "the closed section is flat (no height)");
  }
  const size_t top = SplitIndex(&p, 0, p.size() - 1, 1.0, tolerance);
  std::rotate(p.begin(), p.begin() + static_cast<std::ptrdiff_t>(top), p.end());
  p.push_back(p.front());
  const size_t bottom = SplitIndex(&p, 1, p.size() - 2, -1.0, tolerance);
  a->assign(p.begin(), p.begin() + static_cast<std::ptrdiff_t>(bottom + 1));
  b->assign(p.rbegin(), p.rbegin() + static_cast<std::ptrdiff_t>(p.size() - bottom));
}

}  // namespace

void ProfileOptions::Check() const {
  CANDI_CHECK_OPTION_GE(samples_per_side, 2);
  CANDI_CHECK_OPTION_IN(tie_tolerance, 0, 1e-3);
}

Profile BuildProfile(const ProfileOptions& options, const Polyline2& section,
                     const SectionSource& source) {
  options.Check();
  for (const Eigen::Vector2d& p : section.points) {
    if (!p.allFinite()) FailSection(source, "a vertex is not finite");
  }
  Profile profile;
  profile.source = source;
  const double raw_extent = section.points.empty() ? 0.0 : Extent(section.points);
  const Polyline2 line = MergeCoincidentVertices(section, 1e-12 * raw_extent);
  if (line.points.size() < 3) {
    FailSection(source, "the section has " + std::to_string(line.points.size()) +
                            " distinct vertices; at least 3 are needed");
  }
  profile.extent = Extent(line.points);
  profile.closed = line.closed;
  profile.section_vertices = line.points.size();
  std::vector<Eigen::Vector2d> a, b;
  SplitSides(line, options.tie_tolerance * profile.extent, source, &a, &b);
  const Eigen::Vector2d reference = a.front();
  profile.origin = Eigen::Vector2d(std::round(reference.x()), std::round(reference.y()));
  if (a.size() < 2 || b.size() < 2) {
    if (!options.mirror_single_side) {
      FailSection(source,
                  "the highest point " + FormatDouble(reference.x()) + ", " +
                      FormatDouble(reference.y()) +
                      " is an end of the line, so one side is empty (draw both sides, or allow "
                      "mirroring the half-section)");
    }
    std::vector<Eigen::Vector2d>& present = a.size() < 2 ? b : a;
    std::vector<Eigen::Vector2d>& empty = a.size() < 2 ? a : b;
    empty = present;
    for (Eigen::Vector2d& p : empty) p.x() = 2 * reference.x() - p.x();
    profile.mirrored_single_side = true;
  }
  for (auto* side : {&a, &b}) {
    for (Eigen::Vector2d& p : *side) p -= profile.origin;
  }
  const bool a_left =
      a.back().x() != b.back().x() ? a.back().x() < b.back().x() : MeanX(a) <= MeanX(b);
  profile.reference = reference - profile.origin;
  profile.left = ResampleByArcLength(a_left ? a : b, options.samples_per_side);
  profile.right = ResampleByArcLength(a_left ? b : a, options.samples_per_side);
  return profile;
}

}  // namespace candi::mesh

// Stage 4 of the section lines (section_lines_internal.h): each path becomes a line, with its
// sharp corners, resampled between its ends and corners, its open ends extended along the
// fitted curve; then the lines in the output frame and order.
#include "section/section_lines_internal.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

namespace candi::section::lines_internal {

namespace {

double Length(const std::vector<Eigen::Vector2d>& p, bool closed) {
  double length = 0;
  for (size_t i = 1; i < p.size(); ++i) length += (p[i] - p[i - 1]).norm();
  if (closed && p.size() > 2) length += (p.front() - p.back()).norm();
  return length;
}

// A point of a line: a vertex with its unit tangent, or a corner (tangent zero).
struct Knot {
  Eigen::Vector2d p;
  Eigen::Vector2d t = Eigen::Vector2d::Zero();
};

// The point at fraction f of the segment from a to b: on the cubic Hermite curve through both
// with their tangents (scaled to the chord's length) when both are known and within 30 degrees
// of the chord, else on the chord. Between vertices on a curve, the Hermite curve stays on it
// (to O(h^4) in the spacing h): no refit needed.
Eigen::Vector2d SegmentPoint(const Knot& a, const Knot& b, double f) {
  const Eigen::Vector2d chord = b.p - a.p;
  const double length = chord.norm();
  if (length == 0 || a.t.isZero() || b.t.isZero()) return a.p + f * chord;
  const Eigen::Vector2d ta = a.t.dot(chord) < 0 ? -a.t : a.t;
  const Eigen::Vector2d tb = b.t.dot(chord) < 0 ? -b.t : b.t;
  if (std::min(ta.dot(chord), tb.dot(chord)) < kCosTangents * length) return a.p + f * chord;
  const double f2 = f * f, f3 = f2 * f;
  return (2 * f3 - 3 * f2 + 1) * a.p + (f3 - 2 * f2 + f) * length * ta + (3 * f2 - 2 * f3) * b.p +
         (f3 - f2) * length * tb;
}

double Length(const std::vector<Knot>& k, size_t begin, size_t end) {
  double length = 0;
  for (size_t i = begin; i + 1 < end; ++i) length += (k[i + 1].p - k[i].p).norm();
  return length;
}

// Points from k[begin] to k[end - 1] at equal steps of about `spacing` along the chords, after
// the ones already in *out (the first is not repeated).
void ResamplePiece(const std::vector<Knot>& k, size_t begin, size_t end, double spacing,
                   std::vector<Eigen::Vector2d>* out) {
  const double length = Length(k, begin, end);
  const size_t steps = std::max<size_t>(1, std::lround(length / spacing));
  size_t seg = begin;
  double seg_start = 0;  // length along the chords at k[seg]
  for (size_t step = 1; step < steps; ++step) {
    const double s = length * static_cast<double>(step) / static_cast<double>(steps);
    double seg_length = (k[seg + 1].p - k[seg].p).norm();
    while (seg + 2 < end && seg_start + seg_length < s) {
      seg_start += seg_length;
      ++seg;
      seg_length = (k[seg + 1].p - k[seg].p).norm();
    }
    const double f = seg_length > 0 ? std::clamp((s - seg_start) / seg_length, 0.0, 1.0) : 0.0;
    out->push_back(SegmentPoint(k[seg], k[seg + 1], f));
  }
  out->push_back(k[end - 1].p);
}

// The knots where the line turns by more than 25 degrees (corners): resampling keeps them.
std::vector<size_t> Corners(const std::vector<Knot>& k, bool closed) {
  std::vector<size_t> corners;
  const size_t n = k.size();
  for (size_t i = closed ? 0 : 1; i < (closed ? n : n - 1); ++i) {
    const Eigen::Vector2d in = k[i].p - k[(i + n - 1) % n].p, out = k[(i + 1) % n].p - k[i].p;
    if (in.dot(out) < 0.906 * in.norm() * out.norm()) corners.push_back(i);
  }
  return corners;
}

// Points at equal steps of about `spacing` between the ends and corners of the line (kept). A
// closed line starts at its first corner.
std::vector<Eigen::Vector2d> Resample(std::vector<Knot> ring, bool closed, double spacing) {
  std::vector<size_t> knots = Corners(ring, closed);
  if (closed) {
    const size_t first = knots.empty() ? 0 : knots[0];
    std::rotate(ring.begin(), ring.begin() + first, ring.end());
    for (size_t& k : knots) k -= first;
    ring.push_back(ring.front());
    const double length = Length(ring, 0, ring.size());
    if (knots.empty() && length < 3 * spacing) spacing = length / 3;
  }
  if (knots.empty() || knots.front() != 0) knots.insert(knots.begin(), 0);
  knots.push_back(ring.size() - 1);
  std::vector<Eigen::Vector2d> out(1, ring.front().p);
  for (size_t k = 0; k + 1 < knots.size(); ++k) {
    ResamplePiece(ring, knots[k], knots[k + 1] + 1, spacing, &out);
  }
  if (closed) out.pop_back();  // the first again
  return out;
}

// Extends the end p.back() along the curve to the farthest point the fit there sees beyond it.
void ExtendEnd(const Context& ctx, std::vector<Eigen::Vector2d>* p, Window* win) {
  if (p->size() < 2) return;
  const Eigen::Vector2d end = p->back(), outward = (end - (*p)[p->size() - 2]).normalized();
  Gather(ctx.grid, end, ctx.scales.radius, win);
  const CurveFit fit = FitCurve(win, outward, ctx.scales);
  if (!fit.ok || fit.support < kMinSupport || fit.t.dot(outward) < kCosTangents) return;
  const double reach = fit.reach_ahead;
  if (reach <= 0.1 * ctx.spacing) return;
  const int steps = static_cast<int>(std::ceil(reach / ctx.spacing));
  for (int k = 1; k <= steps; ++k) p->push_back(end + fit.Offset(reach * k / steps));
}

// Open: u increasing from the first vertex to the last (v if equal). Closed: from the vertex of
// least (u, v), counter-clockwise.
void Canonicalize(Polyline2* line) {
  std::vector<Eigen::Vector2d>& p = line->points;
  auto less = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() != b.x() ? a.x() < b.x() : a.y() < b.y();
  };
  if (!line->closed) {
    if (less(p.back(), p.front())) std::reverse(p.begin(), p.end());
    return;
  }
  double area = 0;
  for (size_t i = 0; i < p.size(); ++i) area += Cross(p[i], p[(i + 1) % p.size()]);
  if (area < 0) std::reverse(p.begin(), p.end());
  std::rotate(p.begin(), std::min_element(p.begin(), p.end(), less), p.end());
}

// The corner between consecutive vertices a and b whose tangents differ by over 60 degrees: where
// their tangent lines meet, if the curve each one sees reaches it (within a quarter spacing);
// else false.
bool Corner(const Context& ctx, const Vertex& a, const Vertex& b, Eigen::Vector2d* corner) {
  const double det = Cross(a.t, b.t);
  if (std::abs(a.t.dot(b.t)) >= 0.5 || det == 0) return false;
  const Eigen::Vector2d rel = b.p - a.p;
  const double along_a = Cross(rel, b.t) / det;  // a.p + along_a a.t = b.p + along_b b.t
  const double along_b = Cross(rel, a.t) / det;
  const double slack = 0.25 * ctx.spacing;
  const int side_a = a.t.dot(rel) > 0 ? 0 : 1, side_b = b.t.dot(rel) < 0 ? 0 : 1;
  const double ahead_a = side_a == 0 ? along_a : -along_a,
               ahead_b = side_b == 0 ? along_b : -along_b;
  if (ahead_a < -slack || ahead_a > a.reach[side_a] + slack) return false;
  if (ahead_b < -slack || ahead_b > b.reach[side_b] + slack) return false;
  *corner = a.p + along_a * a.t;
  return true;
}

// The vertices of a path, with the sharp corners between them (see Corner).
std::vector<Knot> PathKnots(const Context& ctx, const std::vector<Vertex>& v,
                            const std::vector<uint32_t>& ids, bool closed) {
  std::vector<Knot> knots;
  Eigen::Vector2d corner;
  for (size_t i = 0; i < ids.size(); ++i) {
    knots.push_back({v[ids[i]].p, v[ids[i]].t});
    const bool last = i + 1 == ids.size();
    if (last && !closed) break;
    if (Corner(ctx, v[ids[i]], v[ids[last ? 0 : i + 1]], &corner)) knots.push_back({corner});
  }
  return knots;
}

Polyline2 MakeLine(const Context& ctx, const std::vector<Vertex>& v, const PathLine& path,
                   bool closed, Window* win) {
  Polyline2 line;
  line.closed = closed;
  line.points = Resample(PathKnots(ctx, v, path.ids, closed), closed, ctx.spacing);
  if (!closed) {
    ExtendEnd(ctx, &line.points, win);
    if (!path.from_junction) {
      std::reverse(line.points.begin(), line.points.end());
      ExtendEnd(ctx, &line.points, win);
    }
  }
  return line;
}

}  // namespace

// The lines of the forest's paths, in the output frame and order (the file comment).
std::vector<Polyline2> BuildLines(const Context& ctx, const std::vector<Vertex>& vertices,
                                  const std::vector<Edge>& edges, const Forest& forest,
                                  const Eigen::Vector2d& origin) {
  std::vector<std::pair<double, Polyline2>> lines;  // with their lengths
  Window win;
  for (const PathLine& path : SplitPaths(vertices, forest)) {
    if (path.ids.size() < 2) continue;
    // A loop: the ends are linked, or near and their links hold a cycle (a spur at the join).
    const uint32_t first = path.ids.front(), last = path.ids.back();
    const bool closed =
        !path.from_junction && path.ids.size() >= 3 &&
        (Linked(edges, first, last) ||
         (forest.loop[first] && (vertices[first].p - vertices[last].p).norm() <= ctx.max_gap));
    Polyline2 line = MakeLine(ctx, vertices, path, closed, &win);
    const double length = Length(line.points, line.closed);
    if (length < ctx.min_length) continue;
    for (Eigen::Vector2d& p : line.points) p += origin;
    Canonicalize(&line);
    lines.emplace_back(length, std::move(line));
  }
  std::stable_sort(lines.begin(), lines.end(), [](const auto& a, const auto& b) {
    if (a.first != b.first) return a.first > b.first;
    const Eigen::Vector2d &pa = a.second.points.front(), &pb = b.second.points.front();
    return pa.x() != pb.x() ? pa.x() < pb.x() : pa.y() < pb.y();
  });
  std::vector<Polyline2> out;
  for (auto& entry : lines) out.push_back(std::move(entry.second));
  return out;
}

}  // namespace candi::section::lines_internal

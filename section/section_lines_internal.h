// The stages of the section lines (section_lines.h gives the method), private to them: what one
// stage hands to the next, and each stage's entry point. section_lines.cc resolves the options
// and runs the stages in order:
//  1. section_line_spacing.cc: the typical point gap (for the automatic spacing), the noise;
//  2. section_line_cover.cc: vertices on the curves, from robust local fits of the curve
//     (section_line_fit.cc, which stages 1 and 4 use too);
//  3. section_line_links.cc: links between the vertices, their spanning forest, its paths;
//  4. section_line_shape.cc: each path's corners, resampling and ends; the lines' order.
// The points and vertices live in a cell grid (section_line_grid.h). Frame: the points relative to
// the least corner of their bounding box, metres. Include only from section/section_line*.cc and
// their tests.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/polyline.h"
#include "section/section_line_grid.h"

namespace candi::section::lines_internal {

constexpr int kMinSupport = 3;  // inliers of a fit that makes a vertex
// Tangents within 30 degrees: of linked vertices, of a Hermite segment's ends against its chord,
// of the fit at a line's end against the line.
constexpr double kCosTangents = 0.86602540378443865;  // cos 30 degrees

inline double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// ---------------------------------------------------------------------------------------------
// Local robust fit of the curve around an anchor (section_line_fit.cc).

struct FitScales {
  double radius = 1.0;      // window radius R, m
  double tau_start = 0.1;   // first biweight scale, m
  double tau_floor = 0.01;  // least biweight scale, m
  double gap = 0.5;         // the inliers' reach stops at gaps longer than this, m
  bool adaptive = false;    // the scale also stops at 3 x the inlier scale (noise estimation)
};

// The points within R of an anchor, relative to it; the ones the fit uses (all, or an even
// subset of kMaxFitPoints: more add little accuracy and cost time); per-point scratch of the fit.
struct Window {
  std::vector<Eigen::Vector2d> d;
  std::vector<uint32_t> slot;      // in the point grid
  std::vector<Eigen::Vector2d> p;  // the fit's points
  std::vector<double> x, y, w;     // their frame coordinates (x in units of R), spatial weight
  std::vector<double> r;           // scratch
  size_t size() const { return p.size(); }
};

// The curve near the anchor, in the frame (t, n) at the anchor: y = a + b x + c x^2, metres.
struct CurveFit {
  bool ok = false;
  Eigen::Vector2d t = Eigen::Vector2d::UnitX(), n = Eigen::Vector2d::UnitY();
  double a = 0, b = 0, c = 0;
  double tol = 0;                            // inliers lie within tol of the curve, m
  double scale = 0;                          // robust scale of the inliers' residuals, m
  int support = 0;                           // inliers in the window
  double reach_ahead = 0, reach_behind = 0;  // inliers run on this far along +t / -t, m

  Eigen::Vector2d Offset(double x) const { return x * t + (a + (b + c * x) * x) * n; }
  Eigen::Vector2d Tangent(double x) const { return (t + (b + 2 * c * x) * n).normalized(); }
  double Residual(const Eigen::Vector2d& d) const {
    const double x = t.dot(d);
    return n.dot(d) - (a + (b + c * x) * x);
  }
};

// Fills *win with the grid's points within `radius` of `anchor`.
void Gather(const PointGrid& grid, const Eigen::Vector2d& anchor, double radius, Window* win);

// The fit of the curve through the anchor of *win (the best of up to two start directions). With
// a hint, t points along it.
CurveFit FitCurve(Window* win, const Eigen::Vector2d& hint, const FitScales& scales);

// ---------------------------------------------------------------------------------------------
// What the stages hand on.

struct Vertex {
  Eigen::Vector2d p;  // on the curve, relative to the origin
  Eigen::Vector2d t;  // unit tangent
  double reach[2];    // the curve's points seen run on this far along +t and -t, m
};

struct Context {
  PointGrid grid;
  FitScales scales;
  double spacing = 0, max_gap = 0, min_length = 0;
  double noise = 0;  // estimated noise of the points across the curves, m
};

struct Edge {
  uint32_t a, b;  // a < b
  double length;
};

struct Forest {
  std::vector<uint32_t> offset, next;  // adjacency (CSR)
  std::vector<uint8_t> alive;
  std::vector<uint32_t> degree;  // alive neighbours
  std::vector<uint8_t> loop;     // the vertex's links hold a cycle (the tree dropped a link)
};

struct PathLine {
  std::vector<uint32_t> ids;
  bool from_junction = false;  // ids[0] is a vertex of an earlier line
};

// ---------------------------------------------------------------------------------------------
// 1. Spacing and noise (section_line_spacing.cc).

// The typical gap between consecutive points along a curve, m (0 if unknown), from a sample of
// the `finite` finite points of `input`, taken relative to `origin`.
double TypicalPointGap(const std::vector<Eigen::Vector2d>& input, const Eigen::Vector2d& origin,
                       size_t finite);

// Estimates ctx->noise from fits over ctx->grid and raises the fits' least scale to match; the
// fits of the later stages are no longer adaptive.
void AdaptToNoise(Context* ctx);

// 2. Cover (section_line_cover.cc): vertices on the curves, in the grid's order.
std::vector<Vertex> CoverPoints(const Context& ctx);

// 3. Links (section_line_links.cc).

// The links between vertices: continuations along the tangents, then matched ends. Sorted by
// (a, b), unique.
std::vector<Edge> LinkVertices(const std::vector<Vertex>& v, const Context& ctx);
// Whether a and b are linked (edges as LinkVertices gives them).
bool Linked(const std::vector<Edge>& edges, uint32_t a, uint32_t b);
// The minimum spanning forest of the n vertices' links.
Forest SpanningForest(size_t n, std::vector<Edge> edges);
// Removes the spurs shorter than min_length from *f.
void PruneSpurs(const std::vector<Vertex>& v, double min_length, Forest* f);
// The forest's alive vertices as paths: each tree's longest path, then its leftover branches.
std::vector<PathLine> SplitPaths(const std::vector<Vertex>& v, const Forest& f);

// 4. Shape (section_line_shape.cc): the lines of the forest's paths, each with its corners,
// resampled and its ends extended, shifted by `origin` and in the output order.
std::vector<Polyline2> BuildLines(const Context& ctx, const std::vector<Vertex>& vertices,
                                  const std::vector<Edge>& edges, const Forest& forest,
                                  const Eigen::Vector2d& origin);

}  // namespace candi::section::lines_internal

// Section lines: the ordered polylines a surveyor draws through the points of a thin slab of a
// point cloud (a section), from those points projected into the section plane.
//
// Input: #points 2-D points, (u, v) = (horizontal, vertical) in metres in the section plane, in a
// local frame (|u|, |v| up to ~1e4 m), in any order: surface samples within a few mm of one or
// several curves (open curves, closed loops such as a horizontal cut through walls, T/Y
// junctions) at uneven density. Non-finite points are skipped. Output: polylines in the same
// frame and units.
//
// Method (section_lines.cc says why):
//  1. Spacing s: given, or automatic: 2.5 x the typical gap between neighbouring points along a
//     curve (from the median distance to the 2nd nearest neighbour over a sample of at most 2^18
//     points: curves totalling over ~50 km at once should pass `spacing`), at least min_spacing.
//     The noise across the curves is estimated from fits at 256 points.
//  2. Cover: the points are bucketed in cells of side 3s. Each point not yet covered anchors a
//     robust local fit of the curve: iteratively reweighted least squares of a line, then of a
//     quadratic y = a + bx + cx^2, in a frame through the point, over the points within 3s
//     (at most 24 of them), with Tukey biweights whose scale halves from s/4 to max(s/50,
//     3 x noise). The vertex is the fitted curve at the anchor: ON the curve, not inside its
//     bends, and on one of two close parallel curves (the faces of a wall), not between them.
//     It covers the inliers within s/2 along the curve. No vertex comes of a fit with under 3
//     inliers (an isolated point) or a sixth of the window's points (a chord across a corner),
//     nor of one that misses its anchor.
//  3. Links: each vertex links ahead and behind to the neighbour along its tangent (both within
//     15 degrees of the chord) when the data gap between them is at most max_gap; the remaining
//     ends are matched in pairs, those whose curves end nearest each other first (the arms of a
//     corner). A minimum spanning forest of the links, spurs under min_length pruned, is split
//     into lines: each tree's longest path, then the leftover branches from the vertex they hang
//     on. A line whose ends are linked (or near, in a cycle of links) is closed.
//  4. Each line gets its sharp corners (the meeting point of the arms' tangents, where the data
//     reaches it), is resampled at about s between its ends and corners along cubic Hermite
//     curves through the vertices and their tangents, and has its open ends extended along the
//     fitted curve to the last points.
// Order: longest line first (ties: first vertex by u, then v). An open line runs with u
// increasing from its first vertex to its last (v if equal); a closed one starts at its vertex of
// least (u, v) and runs counter-clockwise.
// Accuracy (section_lines_test.cc; curves of radius >= 10 m, 5 points/m, 1 mm noise, s ~0.5 m):
// vertices within ~0.4 mm of the curve on average and 2 mm at most (10 mm where interpolated
// across a gap in the data); chords within about s^2 / (8 R) + 1.5 mm. Limits: curves closer than
// about 2 s may be joined at their ends; sharp corners with few points nearby are cut by up to
// s/2; a T junction gives the bar and a stem that may stop up to about s short of it.
//
// Determinism: the result depends on the options and the set of points only: the same points in
// any order give the same bytes (the points are sorted into cells). Single-threaded. Cost: about
// 0.25 us per point plus 7 us per output vertex: 10^7 points on 1 km of curves take ~2.5 s on
// one core, on 200 km (50 points/m) ~30 s.
// Thread-safety: reentrant (a pure function).
// Failure: invalid options throw std::invalid_argument naming the field (also a spacing that
// would need over 2^31 cells along an axis). Empty input, fewer than 2 distinct finite points
// or points on no curve give an empty result, not an error.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "core/polyline.h"

namespace candi::section {

struct SectionLineOptions {
  double spacing = 0.0;       // vertex spacing along the lines, m; >= 0; 0 = automatic
  double max_gap = 0.0;       // longer gaps with no points break a line, m; >= 0; 0 = 6 x spacing
  double min_length = 0.0;    // shorter lines are dropped, m; >= 0; 0 = 2 x spacing
  double min_spacing = 0.05;  // floor of the automatic spacing, m; > 0
  // Throws std::invalid_argument("SectionLineOptions::field = value; must be ...").
  void Check() const;
};

struct SectionLines {
  std::vector<Polyline2> lines;  // open or closed, (u, v) in metres; order: see the file comment
  double spacing = 0.0;          // the values used (automatic ones resolved), m
  double max_gap = 0.0;
  double min_length = 0.0;
  size_t points = 0;  // input points used (the finite ones)
};

// The section lines through `points` (#points, (u, v) in metres). See the file comment.
SectionLines ExtractSectionLines(const SectionLineOptions& options,
                                 const std::vector<Eigen::Vector2d>& points);

}  // namespace candi::section

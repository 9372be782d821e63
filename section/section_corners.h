// Corners of section lines: where a section crosses an edge of its surface (the apex of a
// foundation profile, the foot of a wall) the true line has a corner, and a vertex fitted to a
// window of points around it (section/section_lines.h) cuts the corner by up to a few
// centimetres. This pass finds such corners from the points themselves and puts a vertex on them.
//
// For each vertex that turns by more than min_turn_deg and more than twice as much as the vertices
// two further on each side (a corner concentrates the turning; a smooth curve, even a tight one,
// turns evenly), the points within `window` x spacing
// of it along the line are ordered by their position along the line; every break among them is
// tried, and two straight lines are fitted (total least squares) to the points before and after
// it. The corner is taken when the two lines explain the points much better than the polyline
// does (their RMS residual is below `gain` times the polyline's) and meet near the vertex: their
// intersection becomes the vertex, and the vertices within the window move onto their side's line.
// Units: metres, the points' frame (local: moderate values). Thread-safe (pure function).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "core/polyline.h"

namespace candi::section {

struct SectionCornerOptions {
  double min_turn_deg = 2;   // a vertex turning less is not tried, degrees, [0, 90]
  double window = 3;         // half-window along the line, in spacings, [1, 20]
  double gain = 0.5;         // the two lines' RMS must be below gain x the polyline's, (0, 1]
  size_t min_side_points = 4;  // points each side needs
  void Check() const;
};

struct SectionCornerSummary {
  size_t corners = 0;  // vertices put on a corner
};

// Refines `lines` (drawn through `points` with vertex spacing `spacing`) in place.
SectionCornerSummary RefineSectionCorners(const SectionCornerOptions& options, const std::vector<Eigen::Vector2d>& points,
                                          double spacing, std::vector<Polyline2>* lines);

}  // namespace candi::section

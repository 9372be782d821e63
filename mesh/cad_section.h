// A layer's vertical section: the pieces a drawing holds on one layer (polylines, splines, LINE
// segments) joined end to end into one polyline, checked for branches, gaps and crossings.
//
// Coordinates are 2-D drawing coordinates in metres: x horizontal, y vertical (up).
// Failures are InputError naming `where` (the file and the layer): no pieces, a branch (three or
// more piece ends meeting), a gap (pieces that do not join; the smallest gap is reported in
// metres), fewer than 3 distinct vertices, a section that crosses itself.
// Thread-safe (pure functions).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/polyline.h"

namespace candi::mesh {

struct SectionOptions {
  // Piece ends closer than this join, m; > 0. CAD snaps ends exactly; the default forgives
  // rounding at survey-scale coordinates (1e6 m carries ~1e-10 m per ulp).
  double join_tolerance = 1e-6;
  // Consecutive vertices closer than this merge into one, m; >= 0.
  double merge_tolerance = 1e-9;
  void Check() const;  // throws std::invalid_argument naming the field
};

// Where a section came from, for messages: InputError(path, "layer '<layer>'", ...).
struct SectionSource {
  std::string path;
  std::string layer;
};

// Throws InputError(source.path, "layer '<layer>'", message).
[[noreturn]] void FailSection(const SectionSource& source, const std::string& message);

// Joins `pieces` (each open or closed) end to end into one polyline: open when the chain has two
// free ends, closed when it is a loop. Coincident consecutive vertices are merged. Throws
// InputError (see the file comment).
Polyline2 AssembleSection(const SectionOptions& options, const std::vector<Polyline2>& pieces,
                          const SectionSource& source);

// Merges consecutive vertices closer than `tolerance` (the first of a run is kept; for a closed
// polyline the last vertex also merges into the first).
Polyline2 MergeCoincidentVertices(const Polyline2& line, double tolerance);

// The first crossing or touching of two non-adjacent segments, if any: `found` with the point
// and the two segment indices (segment k joins points k and k+1, the closing one is size()-1).
struct SelfIntersection {
  bool found = false;
  Eigen::Vector2d point = Eigen::Vector2d::Zero();
  size_t segment_a = 0, segment_b = 0;
};
SelfIntersection FindSelfIntersection(const Polyline2& line);

}  // namespace candi::mesh

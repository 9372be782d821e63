// A section split into its two sides and resampled (ALGORITHMS.md §2, step 1).
//
// The reference point is the highest vertex (largest y). Ties (vertices within tie_tolerance x
// extent of the top) are broken deterministically and independently of the drawing direction:
// a run of consecutive tied vertices (a flat or nearly flat top) splits at its arc-length
// midpoint (inserted as a vertex); separate tied peaks split at the one nearest the mean x of the
// tied vertices, the smaller x on a further tie. The reference splits an open section into two
// sides, each running from the reference outward to one end of the line; a closed section is
// split at the reference and at its lowest vertex (same tie rule), both sides running from the
// top to the bottom. The left side is the one whose far end has the smaller x (on a tie, the
// smaller mean x). Each side is resampled to samples_per_side points with the Fritsch-Carlson
// Hermite curve over arc length (mesh/hermite.h), point 0 being the reference.
//
// A peak at an end of an open line leaves one side empty: with mirror_single_side the drawing is
// read as a half-section and the present side is mirrored about the vertical through the
// reference (so the layer is symmetric and `auto` sweeps it); otherwise InputError.
//
// Frame: the profile's points are local, relative to `origin` (the reference rounded to whole
// metres), so drawings in survey coordinates (1e6 m) keep their digits.
// Failures: InputError naming the file and layer (fewer than 3 distinct vertices, an empty side
// without mirroring). Thread-safe (pure function).
#pragma once

#include <Eigen/Core>
#include <vector>

#include "mesh/cad_section.h"

namespace candi::mesh {

struct ProfileOptions {
  int samples_per_side = 1000;     // N, points per side, >= 2
  double tie_tolerance = 1e-9;     // relative to the section's extent, [0, 1e-3]
  bool mirror_single_side = true;  // peak at a line's end: mirror the one side (else an error)
  void Check() const;              // throws std::invalid_argument naming the field
};

struct Profile {
  SectionSource source;
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();     // drawing coordinates of local (0, 0), m
  Eigen::Vector2d reference = Eigen::Vector2d::Zero();  // the reference point, local, m
  std::vector<Eigen::Vector2d> left, right;             // N points each, local, [0] = reference
  double extent = 0;                  // largest side of the section's bounding box, m
  bool closed = false;                // from a closed section (sides end at its lowest point)
  bool mirrored_single_side = false;  // one side was empty and is the mirror of the other
  size_t section_vertices = 0;        // distinct vertices of the section used
};

Profile BuildProfile(const ProfileOptions& options, const Polyline2& section,
                     const SectionSource& source);

}  // namespace candi::mesh

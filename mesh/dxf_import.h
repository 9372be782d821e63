// DXF import (dxflib) of the 2-D geometry a section drawing holds, grouped by layer.
//
// Read: LWPOLYLINE (bulge arcs tessellated so that no chord strays more than chord_tolerance from
// its arc), 2-D/3-D POLYLINE (its bulges too; polygon and polyface meshes are counted and
// skipped), LINE, SPLINE (its fit points when it has two or more, else its control points: the
// control polygon, logged as an approximation). x and y are kept, z dropped. $INSUNITS scales
// everything to metres (0/absent = unitless: `unitless_scale` metres per unit).
// Only model-space entities count; entities inside block definitions and in paper space are
// counted separately and not used. Binary DXF is rejected (InputError saying so).
// Failures: InputError naming the path: unreadable file, binary DXF, no DXF section structure,
// unknown $INSUNITS code, a piece over max_piece_vertices (declared, read, or after tessellating
// bulges), a vertex/knot count the file cannot hold (named by line and group code: dxflib would
// allocate it up front). Memory stays within a few times the file size plus the pieces' limit.
// Thread-safe (no shared state).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "mesh/cad_section.h"

namespace candi::mesh {

struct DxfReadOptions {
  double chord_tolerance = 0.005;  // m, > 0: largest distance of a bulge arc from its chords
  double unitless_scale = 1.0;     // m per drawing unit when $INSUNITS is 0 or absent, > 0
  // Vertices of one piece at most, > 0: a section profile needs thousands, not millions; a larger
  // one (e.g. a polyline of 10^7 vertices) is refused with InputError instead of filling memory.
  size_t max_piece_vertices = 1000000;
  void Check() const;              // throws std::invalid_argument naming the field
};

struct DxfEntityCounts {
  size_t lwpolylines = 0;
  size_t polylines = 0;        // POLYLINE read as lines (2-D and 3-D)
  size_t polyline_meshes = 0;  // POLYLINE polygon/polyface meshes (skipped)
  size_t lines = 0;
  size_t splines = 0;
  size_t other = 0;  // ARC, CIRCLE, TEXT, HATCH, 3DFACE, ... (not sections)
  size_t Sections() const { return lwpolylines + polylines + lines + splines; }
};

struct DxfDrawing {
  std::string path;
  int insunits = 0;             // the $INSUNITS code (0 = unitless or absent)
  double metres_per_unit = 1;   // the scale applied
  std::string unit_name;        // "metre", "millimetre", ..., "unitless"
  DxfEntityCounts model;        // model-space entities
  DxfEntityCounts blocks;       // entities inside block definitions and in paper space (unused)
  size_t closed_polylines = 0;  // model-space LWPOLYLINE/POLYLINE with the closed flag
  // Model-space pieces by layer name, in file order, metres.
  std::map<std::string, std::vector<Polyline2>> layers;
  std::vector<std::string> LayerNames() const;  // layers holding section pieces, sorted
};

DxfDrawing ReadDxf(const DxfReadOptions& options, const std::string& path);

// Metres per unit for an $INSUNITS code; throws InputError(path, ...) for unknown codes.
double InsUnitsToMetres(int code, double unitless_scale, const std::string& path,
                        std::string* name = nullptr);

// Points of the arc from a to b with DXF bulge `bulge` (tan of a quarter of the included angle,
// positive = counter-clockwise), a excluded, b included, no point farther than chord_tolerance
// from the arc's chords. bulge 0 gives {b}.
std::vector<Eigen::Vector2d> TessellateBulge(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                             double bulge, double chord_tolerance);

}  // namespace candi::mesh

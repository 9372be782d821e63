#include "mesh/dxf_import.h"

#include <dl_creationadapter.h>
#include <dl_dxf.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <memory>
#include <set>
#include <stdexcept>

#include "core/check.h"
#include "core/log.h"
#include "core/text_format.h"

namespace candi::mesh {

namespace {

// A piece as the file gives it: drawing units, with a bulge per vertex.
struct RawPiece {
  std::string layer;
  std::vector<Eigen::Vector3d> vertices;  // x, y, bulge of the segment that starts here
  bool closed = false;
};

enum class Pending { kNone, kPolyline, kPolylineMesh, kSpline };

class Collector : public DL_CreationAdapter {
 public:
  void setVariableInt(const std::string& key, int value, int) override {
    if (key == "$INSUNITS") insunits = value;
  }
  void addBlock(const DL_BlockData&) override { Finish(), in_block_ = true; }
  void endBlock() override { Finish(), in_block_ = false; }

  void addLine(const DL_LineData& d) override {
    Finish();
    ++Counts().lines;
    if (Unused() || (d.x1 == d.x2 && d.y1 == d.y2)) return;
    pieces.push_back({Layer(), {{d.x1, d.y1, 0}, {d.x2, d.y2, 0}}, false});
  }
  void addPolyline(const DL_PolylineData& d) override {
    Finish();
    const bool mesh = (d.flags & (16 | 64)) != 0;
    // dxflib delivers an entity when the next one starts: the type is the previous group 0.
    const bool lw = previous_entity_ == "LWPOLYLINE";
    ++(mesh ? Counts().polyline_meshes : lw ? Counts().lwpolylines : Counts().polylines);
    if (!mesh && (d.flags & 1) && !Unused()) ++closed_polylines;
    Start(mesh ? Pending::kPolylineMesh : Pending::kPolyline, (d.flags & 1) != 0);
  }
  void addVertex(const DL_VertexData& d) override {
    if (pending_ == Pending::kPolyline && Room(current_.vertices)) {
      current_.vertices.emplace_back(d.x, d.y, d.bulge);
    }
  }
  void addSpline(const DL_SplineData& d) override {
    Finish();
    ++Counts().splines;
    Start(Pending::kSpline, (d.flags & 1) != 0);
  }
  void addControlPoint(const DL_ControlPointData& d) override {
    if (Room(control_)) control_.emplace_back(d.x, d.y, 0);
  }
  void addFitPoint(const DL_FitPointData& d) override {
    if (Room(current_.vertices)) current_.vertices.emplace_back(d.x, d.y, 0);
  }
  void endEntity() override { Finish(); }
  void endSequence() override { Finish(); }

  // Counts entity types this reader does not use, by section (dxflib reports them elsewhere).
  void processCodeValuePair(unsigned int code, const std::string& value) override {
    if (code == 0) {
      previous_entity_ = entity_;
      entity_ = value;
      static const std::set<std::string> kKnown = {"SECTION",  "ENDSEC", "EOF",    "BLOCK",
                                                   "ENDBLK",   "VERTEX", "SEQEND", "LWPOLYLINE",
                                                   "POLYLINE", "LINE",   "SPLINE"};
      if (value == "SECTION") expect_section_name_ = true;
      if ((section_ == "ENTITIES" || section_ == "BLOCKS") && !kKnown.count(value)) {
        ++(section_ == "ENTITIES" ? model.other : blocks.other);
      }
    } else if (code == 2 && expect_section_name_) {
      section_ = value;
      expect_section_name_ = false;
    }
  }

  // Called once after parsing: the last entity may still be pending.
  void Flush() { Finish(); }

  explicit Collector(size_t max_piece_vertices) : max_piece_vertices_(max_piece_vertices) {}

  int insunits = 0;
  std::string too_many;  // the first piece over max_piece_vertices ("LWPOLYLINE on layer X")
  DxfEntityCounts model, blocks;
  size_t closed_polylines = 0;
  std::vector<RawPiece> pieces;
  size_t control_polygons = 0;

 private:
  bool Unused() { return in_block_ || getAttributes().isInPaperSpace(); }
  // False (and the piece noted) once a piece holds max_piece_vertices: dxflib cannot be stopped
  // from a callback without leaking its file, so the rest is ignored and ReadDxf refuses the file.
  bool Room(const std::vector<Eigen::Vector3d>& vertices) {
    if (vertices.size() < max_piece_vertices_) return true;
    if (too_many.empty()) {
      too_many = std::string(pending_ == Pending::kSpline ? "SPLINE" : "polyline") + " on layer '" +
                 current_.layer + "'";
    }
    return false;
  }
  DxfEntityCounts& Counts() { return Unused() ? blocks : model; }
  std::string Layer() { return getAttributes().getLayer(); }

  void Start(Pending kind, bool closed) {
    pending_ = kind;
    current_ = {Layer(), {}, closed};
    current_unused_ = Unused();
    control_.clear();
  }

  void Finish() {
    if (pending_ == Pending::kSpline && current_.vertices.size() < 2) {
      current_.vertices = control_;
      if (!control_.empty()) ++control_polygons;
    }
    if ((pending_ == Pending::kPolyline || pending_ == Pending::kSpline) && !current_unused_) {
      pieces.push_back(std::move(current_));
    }
    pending_ = Pending::kNone;
    current_ = {};
  }

  size_t max_piece_vertices_;
  Pending pending_ = Pending::kNone;
  RawPiece current_;
  std::vector<Eigen::Vector3d> control_;
  bool in_block_ = false, expect_section_name_ = false, current_unused_ = false;
  std::string section_, entity_, previous_entity_;
};

// A group code or count as a number (leading digits, like dxflib's parsing; a count beyond int
// is kept whole so that it is refused, whatever dxflib would make of it).
long long GroupInt(const std::string& text) { return std::strtoll(text.c_str(), nullptr, 10); }

// Rejects what dxflib would read as garbage (binary DXF, files without DXF sections) and counts
// it would allocate up front: dxflib sizes its arrays from an entity's declared counts
// (LWPOLYLINE 90 vertices, SPLINE 72 knots / 73 control points / 74 fit points, LEADER 76
// vertices) before reading them, so a count of 10^9 in a small file would allocate 32 GB. Group
// pairs are read as dxflib reads them (fgets of at most 1023 bytes, whitespace stripped).
void CheckAsciiDxf(const std::string& path, size_t max_piece_vertices) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "cannot open the file");
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string head = data.substr(0, 4096);
  if (head.rfind("AutoCAD Binary DXF", 0) == 0) {
    throw InputError(path, "", "binary DXF is not supported; save the drawing as ASCII DXF");
  }
  if (head.find("SECTION") == std::string::npos) {
    throw InputError(path, "", "not a DXF file (no SECTION in its first 4 KiB)");
  }
  size_t pos = 0, line = 0;
  // As C strings: a line is cut at its first NUL ("LWPOLYLINE\0junk" is an LWPOLYLINE to
  // dxflib), and a line starting with NUL leaves the previous value in place, as in dxflib.
  auto next_line = [&](std::string* out) {
    if (pos >= data.size()) return false;
    const size_t newline = data.find('\n', pos);
    const size_t end = std::min({newline == std::string::npos ? data.size() : newline + 1,
                                 pos + 1023, data.size()});
    std::string text = data.substr(pos, end - pos);
    pos = end;
    ++line;
    if (text[0] == '\0') return true;
    text.resize(std::min(text.size(), text.find('\0')));
    const size_t first = text.find_first_not_of(" \t\r\n");
    *out = first == std::string::npos
               ? std::string()
               : text.substr(first, text.find_last_not_of(" \t\r\n") - first + 1);
    return true;
  };
  // Each declared item needs at least one group pair of 4 bytes ("10\n0\n") in the file.
  const size_t most_items = data.size() / 4;
  std::string code, value, entity;
  while (next_line(&code) && next_line(&value)) {
    const long long c = GroupInt(code);
    if (c == 0) {
      entity = value;
      continue;
    }
    const char* what = nullptr;
    if (entity == "LWPOLYLINE" && c == 90) what = "vertices";
    if (entity == "SPLINE" && c == 72) what = "knots";
    if (entity == "SPLINE" && c == 73) what = "control points";
    if (entity == "SPLINE" && c == 74) what = "fit points";
    if (entity == "LEADER" && c == 76) what = "vertices";
    if (!what) continue;
    const long long count = GroupInt(value);
    if (count <= 0) continue;
    const size_t n = static_cast<size_t>(count);
    if (n > max_piece_vertices || n > most_items) {
      throw InputError(path, "line " + std::to_string(line),
                       entity + " declares " + std::to_string(n) + " " + what + " (group code " +
                           std::to_string(c) + "); " +
                           (n > max_piece_vertices
                                ? "more than the limit of " + std::to_string(max_piece_vertices) +
                                      " vertices a piece (DxfReadOptions::max_piece_vertices)"
                                : "the " + std::to_string(data.size()) +
                                      "-byte file cannot hold them"));
    }
  }
}

Polyline2 ToMetres(const RawPiece& raw, double scale, double chord_tolerance,
                    size_t max_vertices, const std::string& path) {
  Polyline2 out;
  out.closed = raw.closed;
  const size_t n = raw.vertices.size();
  if (n == 0) return out;
  out.points.emplace_back(raw.vertices[0].x() * scale, raw.vertices[0].y() * scale);
  const size_t segments = raw.closed ? n : n - 1;
  for (size_t k = 0; k < segments; ++k) {
    const Eigen::Vector3d& a = raw.vertices[k];
    const Eigen::Vector3d& b = raw.vertices[(k + 1) % n];
    const std::vector<Eigen::Vector2d> arc =
        TessellateBulge(a.head<2>() * scale, b.head<2>() * scale, a.z(), chord_tolerance);
    out.points.insert(out.points.end(), arc.begin(), arc.end());
    if (out.points.size() > max_vertices) {
      throw InputError(path, "layer '" + raw.layer + "'",
                       "a piece has more than " + std::to_string(max_vertices) +
                           " vertices once its bulge arcs are tessellated (chord tolerance " +
                           FormatDouble(chord_tolerance) +
                           " m; DxfReadOptions::max_piece_vertices)");
    }
  }
  if (raw.closed) out.points.pop_back();  // the closing arc ends on the first point
  return out;
}

}  // namespace

void DxfReadOptions::Check() const {
  CANDI_CHECK_OPTION(chord_tolerance > 0 && std::isfinite(chord_tolerance), chord_tolerance,
                     "finite and > 0");
  CANDI_CHECK_OPTION(unitless_scale > 0 && std::isfinite(unitless_scale), unitless_scale,
                     "finite and > 0");
  CANDI_CHECK_OPTION_GT(max_piece_vertices, 0);
}

std::vector<std::string> DxfDrawing::LayerNames() const {
  std::vector<std::string> names;
  for (const auto& [name, pieces] : layers) names.push_back(name);
  return names;
}

double InsUnitsToMetres(int code, double unitless_scale, const std::string& path,
                        std::string* name) {
  struct Unit {
    const char* name;
    double metres;
  };
  // AutoCAD's $INSUNITS table (codes 0-20).
  static const Unit kUnits[] = {{"unitless", 0},
                                {"inch", 0.0254},
                                {"foot", 0.3048},
                                {"mile", 1609.344},
                                {"millimetre", 1e-3},
                                {"centimetre", 1e-2},
                                {"metre", 1.0},
                                {"kilometre", 1e3},
                                {"microinch", 0.0254e-6},
                                {"mil", 0.0254e-3},
                                {"yard", 0.9144},
                                {"angstrom", 1e-10},
                                {"nanometre", 1e-9},
                                {"micron", 1e-6},
                                {"decimetre", 0.1},
                                {"decametre", 10.0},
                                {"hectometre", 100.0},
                                {"gigametre", 1e9},
                                {"astronomical unit", 149597870700.0},
                                {"light year", 9460730472580800.0},
                                {"parsec", 3.0856775814913673e16}};
  if (code < 0 || code > 20) {
    throw InputError(path, "$INSUNITS",
                     "unknown unit code " + std::to_string(code) + " (AutoCAD defines 0-20)");
  }
  if (name) *name = kUnits[code].name;
  return code == 0 ? unitless_scale : kUnits[code].metres;
}

std::vector<Eigen::Vector2d> TessellateBulge(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                             double bulge, double chord_tolerance) {
  const double chord = (b - a).norm();
  if (bulge == 0 || !std::isfinite(bulge) || chord == 0) return {b};
  const double angle = 4 * std::atan(bulge);  // signed included angle, (-2 pi, 2 pi)
  const double radius = chord / (2 * std::abs(std::sin(angle / 2)));
  // Each step of angle s keeps the sagitta radius (1 - cos(s/2)) within the tolerance.
  const double max_step = 2 * std::acos(std::max(-1.0, 1 - chord_tolerance / radius));
  const int steps = static_cast<int>(
      std::clamp(std::ceil(std::abs(angle) / std::max(max_step, 1e-9)), 1.0, 100000.0));
  const Eigen::Vector2d dir = (b - a) / chord;
  const Eigen::Vector2d left(-dir.y(), dir.x());
  const Eigen::Vector2d centre = (a + b) / 2 + left * (chord / 2 / std::tan(angle / 2));
  const double start = std::atan2(a.y() - centre.y(), a.x() - centre.x());
  std::vector<Eigen::Vector2d> points;
  for (int k = 1; k < steps; ++k) {
    const double t = start + angle * k / steps;
    points.push_back(centre + radius * Eigen::Vector2d(std::cos(t), std::sin(t)));
  }
  points.push_back(b);
  return points;
}

DxfDrawing ReadDxf(const DxfReadOptions& options, const std::string& path) {
  options.Check();
  CheckAsciiDxf(path, options.max_piece_vertices);
  Collector collector(options.max_piece_vertices);
  DL_Dxf dxf;
  if (!dxf.in(path, &collector)) throw InputError(path, "", "cannot open the file");
  collector.Flush();
  if (!collector.too_many.empty()) {
    throw InputError(path, collector.too_many,
                     "more than " + std::to_string(options.max_piece_vertices) +
                         " vertices in one piece (DxfReadOptions::max_piece_vertices)");
  }
  DxfDrawing drawing;
  drawing.path = path;
  drawing.insunits = collector.insunits;
  drawing.metres_per_unit =
      InsUnitsToMetres(collector.insunits, options.unitless_scale, path, &drawing.unit_name);
  drawing.model = collector.model;
  drawing.blocks = collector.blocks;
  drawing.closed_polylines = collector.closed_polylines;
  for (const RawPiece& raw : collector.pieces) {
    Polyline2 piece = ToMetres(raw, drawing.metres_per_unit, options.chord_tolerance,
                               options.max_piece_vertices, path);
    if (!piece.points.empty()) drawing.layers[raw.layer].push_back(std::move(piece));
  }
  if (collector.control_polygons > 0) {
    LogWarning(path + ": " + std::to_string(collector.control_polygons) +
               " SPLINE(s) without fit points: their control polygons are used");
  }
  return drawing;
}

}  // namespace candi::mesh

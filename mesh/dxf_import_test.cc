#include "mesh/dxf_import.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>

#include "core/check.h"
#include "tests/util/dxf_text.h"
#include "tests/util/input_error.h"
#include "tests/util/test_util.h"

namespace candi::mesh {
namespace {

using testing::DxfText;
using testing::InputErrorMessage;
using testing::TempDir;
using testing::WriteBytes;
using V = Eigen::Vector2d;

DxfDrawing ReadText(const TempDir& dir, const std::string& text, DxfReadOptions o = {}) {
  WriteBytes(dir.File("d.dxf"), text);
  return ReadDxf(o, dir.File("d.dxf"));
}

TEST(DxfReadOptions, DefaultsPassAndBadValuesNameTheField) {
  EXPECT_NO_THROW(DxfReadOptions().Check());
  DxfReadOptions o;
  o.chord_tolerance = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.unitless_scale = -1;
  try {
    o.Check();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("DxfReadOptions::unitless_scale = -1"), std::string::npos);
  }
}

TEST(TessellateBulge, SemicircleStaysOnTheArcWithinTheChordTolerance) {
  const double tol = 1e-3;
  const auto pts = TessellateBulge(V(-1, 0), V(1, 0), 1.0, tol);  // counter-clockwise half turn
  ASSERT_GE(pts.size(), 10u);
  EXPECT_EQ(pts.back(), V(1, 0));
  V prev(-1, 0);
  for (const V& p : pts) {
    EXPECT_NEAR(p.norm(), 1.0, 1e-12);
    EXPECT_LE(p.y(), 1e-12) << "positive bulge from (-1,0) to (1,0) passes below";
    const double sagitta = 1.0 - ((p + prev) / 2).norm();
    EXPECT_LE(sagitta, tol * (1 + 1e-9));
    prev = p;
  }
  const auto flipped = TessellateBulge(V(-1, 0), V(1, 0), -1.0, tol);
  EXPECT_GT(flipped[flipped.size() / 2].y(), 0.9);
  EXPECT_EQ(TessellateBulge(V(0, 0), V(1, 0), 0.0, tol).size(), 1u);
  // A quarter circle (bulge tan(pi/8)) of radius 5 about (0, 0) from (5, 0) to (0, 5).
  const auto quarter = TessellateBulge(V(5, 0), V(0, 5), std::tan(M_PI / 8), 1e-4);
  for (const V& p : quarter) EXPECT_NEAR(p.norm(), 5.0, 1e-12);
}

TEST(ReadDxf, LwPolylineWithBulgesPolylineLinesSplineAndLayers) {
  TempDir dir;
  DxfText text;
  text.LwPolyline("D", {V(-2, 0), V(-1, 1), V(1, 1), V(2, 0)}, {0, 1.0, 0})
      .Polyline("A", {V(-3, -1), V(0, 2), V(3, -1)})
      .Lines("B", {V(-4, -2), V(0, 0), V(4, -2)})
      .Spline("C", {V(-5, -3), V(0, -1), V(5, -3)}, {V(-5, -3), V(-2, -1), V(2, -1), V(5, -3)})
      .Circle("A", V(0, 0), 1);
  const DxfDrawing d = ReadText(dir, text.str());
  EXPECT_EQ(d.model.lwpolylines, 1u);
  EXPECT_EQ(d.model.polylines, 1u);
  EXPECT_EQ(d.model.lines, 2u);
  EXPECT_EQ(d.model.splines, 1u);
  EXPECT_EQ(d.model.other, 1u) << "the CIRCLE";
  EXPECT_EQ(d.LayerNames(), (std::vector<std::string>{"A", "B", "C", "D"}));
  EXPECT_EQ(d.unit_name, "metre");
  ASSERT_EQ(d.layers.at("D").size(), 1u);
  const auto& lw = d.layers.at("D")[0].points;
  EXPECT_GT(lw.size(), 10u) << "the bulge arc is tessellated";
  for (size_t k = 2; k + 2 < lw.size(); ++k) EXPECT_NEAR((lw[k] - V(0, 1)).norm(), 1.0, 1e-9);
  EXPECT_EQ(d.layers.at("A")[0].points, (std::vector<V>{V(-3, -1), V(0, 2), V(3, -1)}));
  EXPECT_EQ(d.layers.at("B").size(), 2u);
  EXPECT_EQ(d.layers.at("C")[0].points, (std::vector<V>{V(-5, -3), V(0, -1), V(5, -3)}))
      << "fit points are preferred to control points";
}

TEST(ReadDxf, SplineWithoutFitPointsUsesItsControlPoints) {
  TempDir dir;
  const DxfDrawing d = ReadText(dir, DxfText().Spline("C", {}, {V(0, 0), V(1, 2), V(2, 0)}).str());
  EXPECT_EQ(d.layers.at("C")[0].points, (std::vector<V>{V(0, 0), V(1, 2), V(2, 0)}));
}

TEST(ReadDxf, InsUnitsScaleToMetres) {
  TempDir dir;
  const std::vector<V> pts = {V(-1000, 0), V(0, 2000), V(1000, 0)};
  DxfDrawing d = ReadText(dir, DxfText(4).Polyline("A", pts).str());
  EXPECT_EQ(d.unit_name, "millimetre");
  EXPECT_NEAR(d.layers.at("A")[0].points[1].y(), 2.0, 1e-15);
  d = ReadText(dir, DxfText(1).Polyline("A", pts).str());
  EXPECT_NEAR(d.layers.at("A")[0].points[1].y(), 2000 * 0.0254, 1e-12);
  DxfReadOptions o;
  o.unitless_scale = 0.5;
  d = ReadText(dir, DxfText(-1).Polyline("A", pts).str(), o);
  EXPECT_EQ(d.unit_name, "unitless");
  EXPECT_EQ(d.layers.at("A")[0].points[1].y(), 1000);
  const std::string message =
      InputErrorMessage([&] { ReadText(dir, DxfText(99).Polyline("A", pts).str()); });
  EXPECT_NE(message.find("$INSUNITS"), std::string::npos) << message;
  EXPECT_NE(message.find("99"), std::string::npos) << message;
}

TEST(ReadDxf, PolyfaceMeshesAreCountedAndSkipped) {
  TempDir dir;
  const DxfDrawing d =
      ReadText(dir, DxfText().Polyline("M", {V(0, 0), V(1, 0), V(1, 1)}, false, 64).str());
  EXPECT_EQ(d.model.polyline_meshes, 1u);
  EXPECT_EQ(d.model.polylines, 0u);
  EXPECT_TRUE(d.layers.empty());
}

TEST(ReadDxf, BinaryNonDxfAndMissingFilesAreClearErrors) {
  TempDir dir;
  WriteBytes(dir.File("bin.dxf"), std::string("AutoCAD Binary DXF\r\n\x1a\0", 22) + "junk");
  std::string m = InputErrorMessage([&] { ReadDxf({}, dir.File("bin.dxf")); });
  EXPECT_NE(m.find("binary DXF"), std::string::npos) << m;
  EXPECT_NE(m.find(dir.File("bin.dxf")), std::string::npos) << m;
  WriteBytes(dir.File("text.dxf"), "hello\nworld\n");
  m = InputErrorMessage([&] { ReadDxf({}, dir.File("text.dxf")); });
  EXPECT_NE(m.find("not a DXF"), std::string::npos) << m;
  m = InputErrorMessage([&] { ReadDxf({}, dir.File("none.dxf")); });
  EXPECT_NE(m.find(dir.File("none.dxf")), std::string::npos) << m;
}

// Issue 9's limit: dxflib allocates an LWPOLYLINE's declared vertex count (group 90) before
// reading the vertices, so a declared 10^7 is refused before dxflib sees the file.
TEST(ReadDxf, DeclaredVertexCountsBeyondTheLimitOrTheFileAreRefused) {
  TempDir dir;
  const std::string text =
      DxfText().LwPolyline("A", {V(0, 0), V(1, 0), V(1, 1)}).Line("B", V(0, 0), V(2, 2)).str();
  const size_t at = text.find("90\n3\n");
  ASSERT_NE(at, std::string::npos);
  std::string huge = text;
  huge.replace(at, 6, "90\n10000000\n");
  std::string m = InputErrorMessage([&] { ReadText(dir, huge); });
  EXPECT_NE(m.find(dir.File("d.dxf")), std::string::npos) << m;
  EXPECT_NE(m.find("LWPOLYLINE declares 10000000 vertices (group code 90)"), std::string::npos) << m;
  EXPECT_NE(m.find("limit of 1000000"), std::string::npos) << m;
  const size_t line = std::count(text.begin(), text.begin() + at, '\n') + 2;  // the count's line
  EXPECT_NE(m.find("line " + std::to_string(line)), std::string::npos) << m;
  std::string big = text;
  big.replace(at, 6, "90\n50000\n");  // under the limit, but the file is ~300 bytes
  m = InputErrorMessage([&] { ReadText(dir, big); });
  EXPECT_NE(m.find("cannot hold them"), std::string::npos) << m;
  // dxflib reads lines as C strings: "LWPOLYLINE\0junk" is an LWPOLYLINE and its count counts
  // (fuzz_dxf found a 20000000-vertex allocation this way; fuzz/regressions/dxf).
  std::string nul = text;
  nul.replace(at, 6, "90\n20000000\n");
  const size_t entity = nul.find("LWPOLYLINE\n");
  nul.replace(entity, 11, std::string("LWPOLYLINE\0\0junk\n", 17));
  m = InputErrorMessage([&] { ReadText(dir, nul); });
  EXPECT_NE(m.find("LWPOLYLINE declares 20000000 vertices"), std::string::npos) << m;
  // A count beyond int is refused whole (not wrapped to 3).
  std::string wrapped = text;
  wrapped.replace(at, 6, "90\n4294967299\n");
  m = InputErrorMessage([&] { ReadText(dir, wrapped); });
  EXPECT_NE(m.find("declares 4294967299 vertices"), std::string::npos) << m;
}

TEST(ReadDxf, PiecesOverTheVertexLimitAreRefused) {
  TempDir dir;
  DxfReadOptions o;
  o.max_piece_vertices = 10;
  std::vector<V> points;
  for (int k = 0; k < 11; ++k) points.push_back(V(k, k % 2));
  std::string m = InputErrorMessage([&] { ReadText(dir, DxfText().Polyline("P", points).str(), o); });
  EXPECT_NE(m.find("layer 'P'"), std::string::npos) << m;
  EXPECT_NE(m.find("more than 10 vertices"), std::string::npos) << m;
  points.pop_back();
  EXPECT_EQ(ReadText(dir, DxfText().Polyline("P", points).str(), o).layers.at("P")[0].points.size(),
            10u);
  // Two vertices, but a bulge of 10^9 (almost a full circle of a huge radius) tessellates into
  // far more than 10 points.
  m = InputErrorMessage(
      [&] { ReadText(dir, DxfText().LwPolyline("Q", {V(0, 0), V(1, 0)}, {1e9}).str(), o); });
  EXPECT_NE(m.find("layer 'Q'"), std::string::npos) << m;
  EXPECT_NE(m.find("tessellated"), std::string::npos) << m;
  o.max_piece_vertices = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

// An independent count of entity types by section, from the raw group pairs.
std::map<std::string, size_t> ScanEntities(const std::string& path, const std::string& section) {
  std::ifstream in(path);
  std::map<std::string, size_t> counts;
  std::string code, value, current;
  bool name_next = false;
  auto trim = [](std::string s) {
    s.erase(0, s.find_first_not_of(" \t\r"));
    s.erase(s.find_last_not_of(" \t\r") + 1);
    return s;
  };
  while (std::getline(in, code) && std::getline(in, value)) {
    code = trim(code);
    value = trim(value);
    if (code == "0" && value == "SECTION")
      name_next = true;
    else if (code == "2" && name_next)
      current = value, name_next = false;
    else if (code == "0" && current == section)
      ++counts[value];
  }
  return counts;
}

TEST(ReadDxf, EverySharedDrawingImportsWithCheckedCountsOrFailsClearly) {
  CANDI_REQUIRE_SHARED_DATA(folder, "dxf");
  size_t imported = 0, rejected = 0;
  for (const auto& entry : std::filesystem::directory_iterator(folder)) {
    const std::string path = entry.path().string();
    SCOPED_TRACE(path);
    DxfDrawing d;
    try {
      d = ReadDxf({}, path);
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("binary DXF"), std::string::npos) << e.what();
      EXPECT_NE(path.find("bin_dxf"), std::string::npos) << "only the binary drawing fails";
      ++rejected;
      continue;
    }
    ++imported;
    const auto model = ScanEntities(path, "ENTITIES");
    auto count = [&](const char* type) { return model.count(type) ? model.at(type) : 0; };
    EXPECT_EQ(d.model.lwpolylines, count("LWPOLYLINE"));
    EXPECT_EQ(d.model.polylines + d.model.polyline_meshes, count("POLYLINE"));
    EXPECT_EQ(d.model.lines, count("LINE"));
    EXPECT_EQ(d.model.splines, count("SPLINE"));
    const std::string name = entry.path().filename().string();
    const auto blocks = ScanEntities(path, "BLOCKS");
    auto in_blocks = [&](const char* type) { return blocks.count(type) ? blocks.at(type) : 0; };
    EXPECT_EQ(
        d.blocks.lwpolylines + d.blocks.polylines + d.blocks.lines + d.blocks.splines +
            d.blocks.polyline_meshes,
        in_blocks("LWPOLYLINE") + in_blocks("POLYLINE") + in_blocks("LINE") + in_blocks("SPLINE"));
    if (name == "small_r13.dxf") {
      // (Its block definitions are empty, whatever the data README says.)
      EXPECT_EQ(d.model.polylines + d.model.polyline_meshes, 16u);
    }
    if (name == "POLI-ALL210_12.DXF") {
      EXPECT_EQ(d.model.polylines, 30u);
      EXPECT_EQ(d.closed_polylines, 14u);
    }
    if (name == "uncommon.dxf") {
      EXPECT_GE(d.model.splines, 1u);
      EXPECT_GE(d.model.lwpolylines, 1u);
    }
  }
  EXPECT_EQ(rejected, 1u);
  EXPECT_EQ(imported, 4u);
}

}  // namespace
}  // namespace candi::mesh

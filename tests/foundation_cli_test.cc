// End-to-end tests of `candi foundation`: the bundled example, outputs, exit codes and messages.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/dxf_text.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

using Result = CommandResult;
using V2 = Eigen::Vector2d;

const char kExample[] = "examples/borobudur/foundation.dxf";
const char kQuick[] = " --samples-per-side 120 --angular-steps 36";

// The table row of a layer ("D        green ...").
std::string LayerRow(const std::string& out, const std::string& layer) {
  const size_t at = out.find("\n" + layer + " ");
  if (at == std::string::npos) return "";
  return out.substr(at + 1, out.find('\n', at + 1) - at - 1);
}

TEST(FoundationCli, ExampleBuildsFourCheckedLayersWithExactCountAndLayerField) {
  TempDir dir;
  const Result r = RunCandi(std::string("foundation ") + kExample + " -o " + dir.File("f.ply") +
                            kQuick + " --count 40000 --layers A,B,C,D --mesh " + dir.File("m.obj"));
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* layer : {"A", "B", "C", "D"}) {
    const std::string row = LayerRow(r.out, layer);
    SCOPED_TRACE(row);
    ASSERT_FALSE(row.empty()) << r.out;
    EXPECT_NE(row.find(layer[0] == 'D' ? " yes " : " no "), std::string::npos) << "symmetric?";
    EXPECT_NE(row.find("manifold, open"), std::string::npos);
    EXPECT_NE(row.find("no self-intersections, outward oriented"), std::string::npos);
    EXPECT_TRUE(FileExists(dir.File(std::string("m_") + layer + ".obj")));
  }
  EXPECT_NE(LayerRow(r.out, "D").find("green"), std::string::npos);
  EXPECT_NE(LayerRow(r.out, "A").find("blue"), std::string::npos);
  EXPECT_NE(r.out.find("units millimetre"), std::string::npos) << r.out;
  const PointCloud cloud = io::ReadPointCloud(dir.File("f.ply"));
  ASSERT_EQ(cloud.size(), 40000u);
  ASSERT_TRUE(cloud.schema.layers);
  ASSERT_TRUE(cloud.schema.colors);
  std::map<int, size_t> per_layer;
  for (uint16_t l : cloud.layers) ++per_layer[l];
  EXPECT_EQ(per_layer.size(), 4u);
  for (const auto& [layer, n] : per_layer) EXPECT_GT(n, 5000u) << layer;
  // Within the drawing: each layer turns about the vertical through its peak (A's at x = 12 m,
  // its far side at x = -85 m, 97 m away); heights between -30 and 20 m.
  for (size_t i = 0; i < cloud.size(); i += 97) {
    const Eigen::Vector3d p = cloud.WorldPosition(i);
    EXPECT_LE(std::hypot(p.x(), p.y()), 97.0 + 12.0 + 1e-6);
    EXPECT_GE(p.z(), -30.0 - 1e-6);
    EXPECT_LE(p.z(), 20.0 + 1e-6);
  }
}

TEST(FoundationCli, SplitWritesOnePointFilePerLayerAndModesCanBeForced) {
  TempDir dir;
  const Result r = RunCandi(std::string("-q foundation ") + kExample + " -o " + dir.File("f.xyz") +
                            kQuick + " --density 2 --split --mode sweep " + "--layers B,D");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(FileExists(dir.File("f_B.xyz")));
  EXPECT_TRUE(FileExists(dir.File("f_D.xyz")));
  EXPECT_FALSE(FileExists(dir.File("f.xyz")));
  EXPECT_NE(LayerRow(r.out, "B").find(" sweep "), std::string::npos) << r.out;
}

TEST(FoundationCli, PaperModeAndSurveyCoordinatesKeepTheWorldPosition) {
  TempDir dir;
  const V2 shift(712345.0, 9123456.0);
  std::vector<V2> pts = {V2(-30, 0), V2(-10, 6), V2(0, 9), V2(12, 5), V2(35, -2)};
  for (V2& p : pts) p += shift;
  testing::WriteBytes(dir.File("s.dxf"), DxfText().LwPolyline("hill", pts).str());
  const Result r = RunCandi("foundation " + dir.File("s.dxf") + " -o " + dir.File("s.ply") +
                            kQuick + " --per-triangle 1");
  ASSERT_EQ(r.code, 0) << r.output;
  const PointCloud cloud = io::ReadPointCloud(dir.File("s.ply"));
  EXPECT_EQ(cloud.size(), 2u * 36 * (2 * 119 - 1)) << "one point per triangle";
  for (size_t i = 0; i < cloud.size(); i += 101) {
    const Eigen::Vector3d p = cloud.WorldPosition(i);
    EXPECT_NEAR(p.x(), shift.x(), 40);
    EXPECT_NEAR(p.z(), shift.y(), 40);
  }
}

TEST(FoundationCli, BadOptionValuesAreExitOne) {
  TempDir dir;
  const std::string base = std::string("foundation ") + kExample + " -o " + dir.File("o.ply");
  Result r = RunCandi(base + " --samples-per-side 1");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("ProfileOptions::samples_per_side = 1"), std::string::npos) << r.output;
  r = RunCandi(base + " --angular-steps 1");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("angular_steps = 1"), std::string::npos) << r.output;
  EXPECT_EQ(RunCandi(base + " --mode spin").code, 1);
  EXPECT_EQ(RunCandi(base + " --count 10 --density 3").code, 1);
  r = RunCandi(base + " --density -1");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("density = -1"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("o.ply")));
}

TEST(FoundationCli, BadInputsAreExitTwoNamingFileAndLayer) {
  TempDir dir;
  const std::string out = " -o " + dir.File("o.ply") + kQuick;
  Result r = RunCandi("foundation " + dir.File("none.dxf") + out);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find(dir.File("none.dxf")), std::string::npos) << r.output;
  r = RunCandi(std::string("foundation ") + kExample + out + " --layers A,Z");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("layer 'Z': no such layer"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("(the drawing has: A, B, C, D)"), std::string::npos) << r.output;
  testing::WriteBytes(dir.File("x.dxf"),
                      DxfText().Lines("L", {V2(0, 0), V2(2, 2), V2(2, 0), V2(0, 2)}).str());
  r = RunCandi("foundation " + dir.File("x.dxf") + out);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("layer 'L': the section crosses itself"), std::string::npos) << r.output;
  testing::WriteBytes(dir.File("g.dxf"),
                      DxfText().Line("G", V2(0, 0), V2(1, 1)).Line("G", V2(1.25, 1), V2(2, 0)).str());
  r = RunCandi("foundation " + dir.File("g.dxf") + out);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("smallest gap is 0.25 m"), std::string::npos) << r.output;
  testing::WriteBytes(dir.File("b.dxf"), std::string("AutoCAD Binary DXF\r\n\x1a\0", 22));
  r = RunCandi("foundation " + dir.File("b.dxf") + out);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("binary DXF is not supported"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("o.ply")));
}

}  // namespace
}  // namespace candi::testing

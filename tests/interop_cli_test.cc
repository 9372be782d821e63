// Interop of `candi build`'s archive with the real tools (issue 7): the MeshLab project and its
// local float PLYs opened by `meshlabserver` (under `xvfb-run`), the layer PLYs by CloudCompare's
// command line (QT_QPA_PLATFORM=offscreen); what the tools write back is read with candi's own
// reader and checked: point counts, colours, the fields each tool keeps, coordinates.
//
// Facts these tests pin (Debian 12: MeshLab 2020.09, CloudCompare 2.11.3):
// - MeshLab reads PLY coordinates as float; it keeps colour and `quality`, drops other properties
//   (scalar_scene_layer); a project's <MLMatrix44> is written back unchanged, not applied.
// - CloudCompare loads vertex properties whose name contains "scal" as scalar fields (so
//   scalar_scene_layer, written back under the same name; `quality` is not loaded) and ignores
//   candi's shift comment. In -SILENT mode without -GLOBAL_SHIFT it stores big coordinates in
//   float and writes float back (millimetres lost at E 416000, N 9168000); with -GLOBAL_SHIFT AUTO
//   it shifts on load and writes double world coordinates back.
// The tools start slowly (~4 s each), so each runs once or twice on all layers together. Absent
// tools skip the test, naming the Debian package (scripts/deps.sh installs them).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Result = CommandResult;

bool HaveCommand(const std::string& name) { return RunCommand("command -v " + name + " >/dev/null").code == 0; }

#define REQUIRE_TOOL(command, package)                                                              \
  if (!HaveCommand(command)) {                                                                      \
    GTEST_SKIP() << "'" << (command) << "' is not installed (Debian package " << (package)           \
                 << "; scripts/deps.sh installs it); skipping";                                      \
  }

struct Layer {
  std::string name;
  size_t count;
  Rgb8 color;
};
// The scene's layers, in scene order (their index is scalar_scene_layer).
const std::vector<Layer> kLayers = {{"wall", 1200, {200, 60, 40}}, {"pillar", 800, {0, 160, 0}},
                                    {"copy", 1200, {200, 60, 40}}};

// A survey-scale scene of three layers with millimetre detail: a wall (PLY, shifted, coloured), a
// pillar (XYZ text in world coordinates, recoloured) and the wall again, moved by world_from_layer.
// Built into dir/out; returns candi's output.
Result BuildScene(const TempDir& dir) {
  PointCloud wall;
  wall.schema.colors = true;
  wall.SetSchema(wall.schema);
  wall.frame.origin = Eigen::Vector3d(416000, 9168000, 250);
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 30; ++j) {
      wall.positions.emplace_back(0.05 * i + 0.0007, 5.0 + 0.0003 * j, 0.05 * j + 0.0009);
      wall.colors.push_back(kLayers[0].color);
    }
  io::WritePointCloud(dir.File("wall.ply"), wall);
  std::string xyz;
  char line[128];
  for (int i = 0; i < 800; ++i) {
    std::snprintf(line, sizeof(line), "%.4f %.4f %.4f\n", 416003.1234 + 0.001 * (i % 20),
                  9168002.5678 + 0.002 * (i / 20), 251.0009 + 0.003 * i);
    xyz += line;
  }
  testing::WriteBytes(dir.File("pillar.xyz"), xyz);
  const json scene = {
      {"candi_scene", 1}, {"name", "interop"}, {"seed", 3},
      {"layers",
       {{{"name", "wall"}, {"kind", "points"}, {"file", "wall.ply"}},
        {{"name", "pillar"}, {"kind", "points"}, {"file", "pillar.xyz"}, {"columns", "x,y,z"}, {"color", {0, 160, 0}}},
        {{"name", "copy"}, {"kind", "points"}, {"file", "wall.ply"},
         {"world_from_layer", {{"translation", {0.25, -0.5, 1.0}}}}}}}};
  testing::WriteBytes(dir.File("scene.json"), scene.dump(2));
  return RunCandi("-q build " + dir.File("scene.json") + " -o " + dir.File("out"));
}

// World coordinates of layer k as candi wrote it (layers/<name>.ply, read by candi).
std::vector<Eigen::Vector3d> WorldOf(const TempDir& dir, size_t k) {
  const PointCloud c = io::ReadPointCloud(dir.File("out/layers/" + kLayers[k].name + ".ply"));
  std::vector<Eigen::Vector3d> world;
  for (size_t i = 0; i < c.size(); ++i) world.push_back(c.WorldPosition(i));
  return world;
}

// Largest distance between corresponding points (their order kept by the tools).
double MaxDistance(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  EXPECT_EQ(a.size(), b.size());
  double d = 0;
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i) d = std::max(d, (a[i] - b[i]).norm());
  return d;
}

// Checks a file a tool wrote for layer k: count, colours, the field `field` (= k).
void ExpectLayer(const PointCloud& c, size_t k, const std::string& field) {
  SCOPED_TRACE(kLayers[k].name + ", field " + field);
  ASSERT_EQ(c.size(), kLayers[k].count);
  ASSERT_TRUE(c.schema.colors);
  const ScalarField* f = c.FindScalar(field);
  ASSERT_NE(f, nullptr) << "the field did not survive";
  for (size_t i = 0; i < c.size(); i += 37) {
    EXPECT_EQ(c.colors[i], kLayers[k].color) << i;
    EXPECT_EQ(f->Get(i), static_cast<double>(k)) << i;
  }
}

// One <MLMesh> of a MeshLab project: filename and its 4 x 4 matrix.
struct MlMesh {
  std::string filename;
  Eigen::Matrix4d matrix;
};
std::vector<MlMesh> ReadMlp(const std::string& path) {
  const std::string text = testing::ReadBytes(path);
  std::vector<MlMesh> meshes;
  for (size_t at = text.find("<MLMesh"); at != std::string::npos; at = text.find("<MLMesh", at + 1)) {
    MlMesh m;
    const size_t f = text.find("filename=\"", at) + 10;
    m.filename = text.substr(f, text.find('"', f) - f);
    const size_t open = text.find("<MLMatrix44>", at) + 12;
    std::istringstream numbers(text.substr(open, text.find("</MLMatrix44>", open) - open));
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) numbers >> m.matrix(r, c);
    EXPECT_FALSE(numbers.fail()) << path << ": matrix of " << m.filename;
    meshes.push_back(m);
  }
  return meshes;
}

// meshlab/shift.txt: a comment line, then "x y z".
Eigen::Vector3d ReadShift(const std::string& path) {
  std::istringstream in(testing::ReadBytes(path));
  std::string comment;
  std::getline(in, comment);
  Eigen::Vector3d s;
  in >> s.x() >> s.y() >> s.z();
  EXPECT_FALSE(in.fail()) << path;
  return s;
}

TEST(Interop, MeshLabOpensTheProjectAndTheLocalPlysKeepingQualityAndColour) {
  REQUIRE_TOOL("meshlabserver", "meshlab");
  REQUIRE_TOOL("xvfb-run", "xvfb");
  TempDir dir;
  const Result built = BuildScene(dir);
  ASSERT_EQ(built.code, 0) << built.output;
  // MeshLab writes <mesh>_out.ply beside a project's meshes: work on a copy of meshlab/.
  fs::copy(dir.File("out/meshlab"), dir.File("ml"));
  const std::string ml = dir.File("ml/");
  const Eigen::Vector3d shift = ReadShift(ml + "shift.txt");
  EXPECT_EQ(shift, shift.array().round().matrix().eval()) << "an integer shift";
  EXPECT_GT(shift.x(), 4e5) << "survey coordinates: a shift was chosen";

  // 1. The project: loaded, saved back as a project (-w, every attribute) and layer by layer (-o
  //    with colour and quality).
  std::string project = "timeout 120 xvfb-run -a meshlabserver -p " + ml + "scene.mlp -w " + ml + "saved.mlp";
  // 2. Each local PLY on its own.
  std::string plys = "timeout 120 xvfb-run -a meshlabserver";
  for (size_t k = 0; k < kLayers.size(); ++k) {
    project += " -o " + ml + "p_" + kLayers[k].name + ".ply -l " + std::to_string(k) + " -m vc vq";
    plys += " -i " + ml + kLayers[k].name + ".ply";
  }
  for (size_t k = 0; k < kLayers.size(); ++k)
    plys += " -o " + ml + "i_" + kLayers[k].name + ".ply -l " + std::to_string(k) + " -m vc vq";
  for (const std::string& command : {project, plys}) {
    const Result r = RunCommand(command);
    ASSERT_EQ(r.code, 0) << command << "\n" << r.output;
  }

  const std::vector<MlMesh> saved = ReadMlp(ml + "saved.mlp");
  ASSERT_EQ(saved.size(), kLayers.size());
  for (size_t k = 0; k < kLayers.size(); ++k) {
    SCOPED_TRACE(kLayers[k].name);
    const PointCloud local = io::ReadPointCloud(ml + kLayers[k].name + ".ply");  // what candi wrote
    ASSERT_TRUE(local.frame.IsIdentity());
    for (const char* prefix : {"p_", "i_"}) {
      const PointCloud c = io::ReadPointCloud(ml + prefix + kLayers[k].name + ".ply");
      ExpectLayer(c, k, "quality");
      EXPECT_EQ(c.schema.position_type, ScalarType::kFloat32);
      EXPECT_LT(MaxDistance(c.positions, local.positions), 1e-6) << prefix;  // float in, float out
    }
    // The saved project: the mesh MeshLab wrote (every attribute) with the project's matrix, plus
    // shift.txt, gives the world coordinates of layers/<name>.ply to well under a millimetre.
    EXPECT_EQ(saved[k].filename, kLayers[k].name + "_out.ply");
    EXPECT_TRUE(saved[k].matrix.isIdentity(0.0)) << saved[k].matrix;
    const PointCloud out = io::ReadPointCloud(ml + saved[k].filename);
    ExpectLayer(out, k, "quality");
    std::vector<Eigen::Vector3d> world;
    for (const Eigen::Vector3d& p : out.positions)
      world.push_back((saved[k].matrix * p.homogeneous()).head<3>() + shift);
    EXPECT_LT(MaxDistance(world, WorldOf(dir, k)), 1e-4);
  }
  // The survey detail is there: the wall's first point at E 416000.0007.
  EXPECT_NEAR(WorldOf(dir, 0)[0].x(), 416000.0007, 1e-9);
}

TEST(Interop, CloudCompareKeepsScalarFieldsAndDoubleCoordinatesWithGlobalShiftAuto) {
  REQUIRE_TOOL("CloudCompare", "cloudcompare");
  TempDir dir;
  const Result built = BuildScene(dir);
  ASSERT_EQ(built.code, 0) << built.output;
  fs::create_directories(dir.File("cc"));
  // The layer files hold double world coordinates themselves: CloudCompare ignores candi's shift
  // comment and sidecar.
  for (const Layer& l : kLayers) {
    const io::PointFileInfo info = io::OpenPointReader(dir.File("out/layers/" + l.name + ".ply"))->info();
    EXPECT_TRUE(info.frame.IsIdentity()) << l.name;
    EXPECT_EQ(info.schema.position_type, ScalarType::kFloat64) << l.name;
  }
  // The wall once as CloudCompare opens it by default in -SILENT mode, then every layer with
  // -GLOBAL_SHIFT AUTO; saved under names of our choosing (-NO_TIMESTAMP, -SAVE_CLOUDS FILE).
  std::string command = "timeout 120 env QT_QPA_PLATFORM=offscreen CloudCompare -SILENT -NO_TIMESTAMP "
                        "-C_EXPORT_FMT PLY -O " + dir.File("out/layers/wall.ply");
  std::string names = dir.File("cc/wall_default.ply");
  for (const Layer& l : kLayers) {
    command += " -O -GLOBAL_SHIFT AUTO " + dir.File("out/layers/" + l.name + ".ply");
    names += " " + dir.File("cc/" + l.name + ".ply");
  }
  command += " -SAVE_CLOUDS FILE \"" + names + "\"";
  const Result r = RunCommand(command);
  ASSERT_EQ(r.code, 0) << command << "\n" << r.output;
  EXPECT_NE(r.output.find("recentered"), std::string::npos) << r.output;

  for (size_t k = 0; k < kLayers.size(); ++k) {
    SCOPED_TRACE(kLayers[k].name);
    ASSERT_TRUE(FileExists(dir.File("cc/" + kLayers[k].name + ".ply"))) << r.output;
    const PointCloud c = io::ReadPointCloud(dir.File("cc/" + kLayers[k].name + ".ply"));
    ExpectLayer(c, k, "scene_layer");  // scalar_scene_layer, written back under its name
    EXPECT_EQ(c.schema.position_type, ScalarType::kFloat64);
    std::vector<Eigen::Vector3d> world;
    for (size_t i = 0; i < c.size(); ++i) world.push_back(c.WorldPosition(i));
    EXPECT_LT(MaxDistance(world, WorldOf(dir, k)), 1e-3);
  }
  // Without -GLOBAL_SHIFT: float coordinates, the millimetres (and more) lost at N 9168000.
  const PointCloud plain = io::ReadPointCloud(dir.File("cc/wall_default.ply"));
  ExpectLayer(plain, 0, "scene_layer");
  EXPECT_EQ(plain.schema.position_type, ScalarType::kFloat32);
  std::vector<Eigen::Vector3d> world;
  for (size_t i = 0; i < plain.size(); ++i) world.push_back(plain.WorldPosition(i));
  const double lost = MaxDistance(world, WorldOf(dir, 0));
  EXPECT_GT(lost, 1e-3);
  EXPECT_LT(lost, 1.0);
}

}  // namespace
}  // namespace candi::testing

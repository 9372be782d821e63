// Issue 9's CLI error matrix: every command with file arguments, given a missing input, an output
// folder it cannot write to, and a bad option value, exits with the documented code (2, 2, 1), names
// the culprit, and leaves no output behind.
//
// The unwritable folder: a directory of mode 0500 for a normal user; root ignores permissions, so
// when the tests run as root (CI containers) the output goes under a regular file instead
// (`file.txt/out.ply`), which fails for every user. Commands of candi-pcl (register, clean) and
// candi-relief (demo) run when those executables are built beside candi (they are skipped with
// CANDI_BUILD_RELIEF=OFF or without PCL). Not in the table: `dense` with an unwritable output (it
// needs a COLMAP model first; dense_cli_test covers its inputs), the relief network commands
// (relief_cli_test), and `bench` (no input or output files; only its option values are checked).
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "io/image/png_io.h"
#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

namespace fs = std::filesystem;
using Result = CommandResult;

struct Row {
  const char* command;      // for messages
  const char* executable;   // sibling executable the command needs ("" = candi itself)
  // Arguments with {D} for the test folder, {IN} for a missing input, {OUT} for the output.
  std::string missing;      // a missing input (its path is {D}/missing...)
  std::string unwritable;   // valid inputs, output {OUT} in a folder that cannot be written
  std::string bad_option;   // valid files, one bad option value ("" = not checked here)
  const char* option;       // the option the usage message must name
  const char* out_name;     // the output's file name under the unwritable folder
};

std::string Replace(std::string s, const std::string& from, const std::string& to) {
  for (size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) s.replace(at, from.size(), to);
  return s;
}

bool HaveSibling(const std::string& name) {
  return name.empty() || fs::exists(fs::path(CANDI_EXECUTABLE).parent_path() / name);
}

// Inputs every row can use: a point file, a colour PNG with a colour card CSV, a scene, targets,
// relief correspondences, two photos.
void WriteInputs(const TempDir& dir) {
  PointCloud c;
  c.schema.colors = true;
  c.SetSchema(c.schema);
  for (int i = 0; i < 200; ++i) {
    c.positions.emplace_back(0.01 * (i % 20), 0.01 * (i / 20), 0.001 * i);
    c.colors.push_back({static_cast<uint8_t>(i), 80, 160});
  }
  io::WritePointCloud(dir.File("in.ply"), c);
  io::WritePointCloud(dir.File("in.xyz"), c);
  Image8 rgb(32, 24, 3);
  for (int y = 0; y < 24; ++y)
    for (int x = 0; x < 32; ++x)
      for (int k = 0; k < 3; ++k) rgb.at(x, y, k) = static_cast<uint8_t>(40 + 5 * x + 3 * y + 20 * k);
  io::WritePng(dir.File("img.png"), rgb);
  fs::create_directories(dir.File("photos"));
  io::WritePng(dir.File("photos/a.png"), rgb);
  rgb.at(0, 0, 0) = 7;  // not a copy of a.png (candi sfm leaves copies out)
  io::WritePng(dir.File("photos/b.png"), rgb);
  testing::WriteBytes(dir.File("card.csv"),
                      "patch,measured_r,measured_g,measured_b,reference_r,reference_g,reference_b\n"
                      "1,10,20,30,12,22,32\n2,100,50,30,110,55,33\n3,30,200,60,33,210,66\n"
                      "4,200,200,200,210,210,210\n5,50,60,200,55,66,210\n");
  testing::WriteBytes(dir.File("scene.json"),
                      "{\"candi_scene\": 1, \"layers\": [{\"name\": \"a\", \"kind\": \"points\", \"file\": \"in.ply\"}]}");
  testing::WriteBytes(dir.File("targets.csv"),
                      "name,E,N,H,role,accuracy,x,y,z\nA,100,200,10,control,0.01,0,0,0\n"
                      "B,101,200,10,control,0.01,1,0,0\nC,100,201,10,control,0.01,0,1,0\n"
                      "D,100,200,11,control,0.01,0,0,1\n");
  testing::WriteBytes(dir.File("walls.csv"),
                      "panel,point,x,y,z,E,N,H\nP1,a,0,0,0,100,200,10\nP1,b,2.7,0,0,102.7,200,10\n"
                      "P1,c,2.7,0.92,0,102.7,200,10.92\nP1,d,0,0.92,0,100,200,10.92\n");
}

const char kDxf[] = "examples/borobudur/foundation.dxf";

std::vector<Row> Rows() {
  const std::string dxf = fs::absolute(kDxf).string();
  return {
      {"info", "", "info {IN}.ply", "", "info {D}/in.xyz --columns q", "column spec", ""},
      {"convert", "", "convert {IN}.ply {D}/o.ply", "convert {D}/in.ply {OUT}", "convert {D}/in.ply {D}/o.ply --precision half",
       "--precision", "o.las"},
      {"opacity", "", "opacity {IN}.ply {D}/o.ply --alpha 0.5 --repeat-level 4 --image-size 64",
       "opacity {D}/in.ply {OUT} --alpha 0.5 --repeat-level 4 --image-size 64",
       "opacity {D}/in.ply {D}/o.ply --alpha 1.5 --repeat-level 4 --image-size 64", "alpha", "o.ply"},
      {"render", "", "render {IN}.ply -o {D}/o.png", "render {D}/in.ply -o {OUT} --size 32x24 -L 2",
       "render {D}/in.ply -o {D}/o.png --threads 999", "--threads", "o.png"},
      {"pack", "", "pack {IN}.ply -o {D}/arc", "pack {D}/in.ply -o {OUT}", "pack {D}/in.ply -o {D}/arc --chunk-points 1",
       "--chunk-points", "arc"},
      {"foundation", "", "foundation {IN}.dxf -o {D}/f.ply",
       "foundation " + dxf + " -o {OUT} --layers D --count 500 --samples-per-side 30 --angular-steps 8",
       "foundation " + dxf + " -o {D}/f.ply --mode spin", "--mode", "f.ply"},
      {"build", "", "build {IN}.json -o {D}/b", "build {D}/scene.json -o {OUT}", "build {D}/scene.json -o {D}/b --threads 999",
       "--threads", "b"},
      {"sfm", "", "sfm {IN} -o {D}/w", "sfm {D}/photos -o {OUT}", "sfm {D}/photos -o {D}/w --max-image-size 1",
       "--max-image-size", "w"},
      {"dense", "", "dense {IN} -o {D}/d.ply", "", "dense {D}/photos -o {D}/d.ply --iterations 0", "iterations", ""},
      {"georef", "", "georef {IN}.ply --targets {D}/targets.csv -o {D}/g.ply",
       "georef {D}/in.ply --targets {D}/targets.csv -o {OUT}",
       "georef {D}/in.ply --targets {D}/targets.csv -o {D}/g.ply --loss l1", "--loss", "g.ply"},
      {"colorcorrect", "", "colorcorrect {IN}.png -o {D}/c.png --patches {D}/card.csv",
       "colorcorrect {D}/img.png -o {OUT} --patches {D}/card.csv",
       "colorcorrect {D}/img.png -o {D}/c.png --patches {D}/card.csv --max-outliers -1", "--max-outliers", "c.png"},
      {"relief place", "", "relief place {IN}.csv -o {D}/p.json", "relief place {D}/walls.csv -o {OUT}",
       "relief place {D}/walls.csv -o {D}/p.json --loss l1", "--loss", "p.json"},
      {"bench render", "", "", "", "bench render --width 1", "--width", ""},
      {"register", "candi-pcl", "register {IN}.ply {D}/in.ply -o {D}/r.ply", "register {D}/in.ply {D}/in.ply -o {OUT}",
       "register {D}/in.ply {D}/in.ply -o {D}/r.ply --method curve", "--method", "r.ply"},
      {"clean", "candi-pcl", "clean {IN}.ply -o {D}/c.ply", "clean {D}/in.ply -o {OUT}",
       "clean {D}/in.ply -o {D}/c.ply --sor-k 0", "sor", "c.ply"},  // "CleanOptions::sor_neighbours"
      // demo: libtorch takes seconds to load, so only its output folder (its options are CLI11 ranges).
      {"demo", "candi-relief", "", "demo --quick -o {OUT}", "", "", "demo"},
  };
}

TEST(CliErrors, MissingInputUnwritableOutputAndBadOptionValueForEveryCommand) {
  TempDir dir;
  WriteInputs(dir);
  // The folder that cannot be written (see the top of the file).
  std::string locked;
  if (geteuid() == 0) {
    testing::WriteBytes(dir.File("file.txt"), "a regular file\n");
    locked = dir.File("file.txt");
  } else {
    fs::create_directories(dir.File("locked"));
    ASSERT_EQ(chmod(dir.File("locked").c_str(), 0500), 0);
    locked = dir.File("locked");
  }
  for (const Row& row : Rows()) {
    SCOPED_TRACE(row.command);
    if (!HaveSibling(row.executable)) {
      std::printf("[ note ] %s: skipped, %s is not built\n", row.command, row.executable);
      continue;
    }
    auto args = [&](const std::string& pattern, const std::string& out) {
      return Replace(Replace(Replace(pattern, "{D}", dir.path()), "{IN}", dir.File("missing")), "{OUT}", out);
    };
    if (!row.missing.empty()) {
      const Result r = RunCandi(args(row.missing, ""));
      EXPECT_EQ(r.code, 2) << r.output;
      EXPECT_NE(r.output.find(dir.File("missing")), std::string::npos) << "names the input: " << r.output;
    }
    if (!row.unwritable.empty()) {
      const std::string out = locked + "/" + row.out_name;
      const Result r = RunCandi(args(row.unwritable, out));
      EXPECT_EQ(r.code, 2) << r.output;
      EXPECT_NE(r.output.find(locked), std::string::npos) << "names the output: " << r.output;
      EXPECT_FALSE(fs::exists(out));
    }
    if (!row.bad_option.empty()) {
      const Result r = RunCandi(args(row.bad_option, ""));
      EXPECT_EQ(r.code, 1) << r.output;
      EXPECT_NE(r.output.find(row.option), std::string::npos) << "names the option: " << r.output;
    }
  }
  // The COPC memory budget of convert, build and export copc: a size in MB, never negative or
  // not a number, refused before anything is read or written.
  for (const char* bad : {"-1", "nan"}) {
    for (const std::string& command :
         {"convert " + dir.File("in.ply") + " " + dir.File("o.copc.laz"),
          "build " + dir.File("no_scene.json") + " -o " + dir.File("cb"),
          "export copc " + dir.File("cb") + " -o " + dir.File("o.copc.laz")}) {
      const Result r = RunCandi(command + " --copc-memory " + bad);
      EXPECT_EQ(r.code, 1) << command << ": " << r.output;
      EXPECT_NE(r.output.find("--copc-memory " + std::string(bad) + ": must be >= 0"), std::string::npos)
          << command << ": " << r.output;
      EXPECT_FALSE(fs::exists(dir.File("o.copc.laz")));
      EXPECT_FALSE(fs::exists(dir.File("cb")));
    }
  }
  // Nothing was left behind by the failed commands: only the inputs are in the folder.
  for (const char* output : {"o.ply", "o.png", "arc", "f.ply", "b", "w", "d.ply", "g.ply", "c.png", "c.ply", "p.json", "r.ply", "demo"})
    EXPECT_FALSE(fs::exists(dir.File(output))) << output;
  if (geteuid() != 0) chmod(dir.File("locked").c_str(), 0700);
}

}  // namespace
}  // namespace candi::testing

// End-to-end tests of `candi render`: merged inputs, PNG provenance, determinism, views, modes,
// per-input opacity, exit codes and messages.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <string>

#include "core/rng.h"
#include "io/image/png_io.h"
#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

using Result = CommandResult;

// n points uniform on a 10 x 10 m square at survey coordinates, height z, one colour.
void WriteSquare(const std::string& path, size_t n, double z, Rgb8 color, uint64_t seed) {
  PointCloud c;
  c.schema.colors = true;
  c.SetSchema(c.schema);
  c.Resize(n);
  c.frame.origin = Eigen::Vector3d(500000, 4500000, 0);
  Rng rng(seed);
  for (size_t i = 0; i < n; ++i) {
    c.positions[i] = Eigen::Vector3d(rng.Uniform(0, 10), rng.Uniform(0, 10), z);
    c.colors[i] = color;
  }
  io::WritePointCloud(path, c);
}

// Two squares, red above blue; the view is a top-down orthographic one so every pixel sees both.
struct Scene {
  TempDir dir;
  std::string back, front, view;
  Scene() {
    back = dir.File("back.ply");
    front = dir.File("front.las");
    view = dir.File("view.json");
    WriteSquare(back, 40000, 90.0, {0, 0, 255}, 1);
    WriteSquare(front, 40000, 95.0, {255, 0, 0}, 2);
    WriteBytes(view, R"({"projection": "orthographic", "width": 40, "height": 40,
      "eye": [500005, 4500005, 200], "target": [500005, 4500005, 0], "up": [0, 1, 0],
      "ortho_height": 8})");
  }
  std::string Inputs() const { return back + " " + front; }
};

double MeanChannel(const Image8& image, int channel) {
  double sum = 0;
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) sum += image.at(x, y, channel);
  }
  return sum / (image.width() * image.height());
}

// True when the red pixels' mean row is above the blue pixels' (each colour drawn somewhere).
bool RedAboveBlue(const std::string& png) {
  const Image8 image = io::ReadPng(png).image8;
  double red_rows = 0, blue_rows = 0, reds = 0, blues = 0;
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      if (image.at(x, y, 0) > 128 && image.at(x, y, 2) < 64) red_rows += y, reds += 1;
      if (image.at(x, y, 2) > 128 && image.at(x, y, 0) < 64) blue_rows += y, blues += 1;
    }
  }
  return reds > 20 && blues > 20 && red_rows / reds < blue_rows / blues;
}

// A facade in COLMAP's frame (y down, cameras looking along +z): a red band at the top (y = -2)
// and a blue one at the bottom (y = +2). With --up 0,-1,0 the default view shows red above blue
// (z-up's default shows it upside down or from above); --from parallel to --up is refused.
TEST(RenderCli, UpPutsAColmapFrameFacadeUpright) {
  TempDir dir;
  PointCloud c;
  c.schema.colors = true;
  c.SetSchema(c.schema);
  Rng rng(3);
  for (int i = 0; i < 20000; ++i) {
    const bool top = i % 2 == 0;
    c.positions.push_back(Eigen::Vector3d(rng.Uniform(-4, 4), (top ? -2 : 2) + rng.Uniform(-0.5, 0.5),
                                          rng.Uniform(-0.1, 0.1)));
    c.colors.push_back(top ? Rgb8{255, 0, 0} : Rgb8{0, 0, 255});
  }
  c.Resize(c.positions.size());
  io::WritePointCloud(dir.File("facade.ply"), c);
  const std::string out = dir.File("up.png");
  const Result r = RunCandi("render " + dir.File("facade.ply") + " -o " + out +
                            " --up 0,-1,0 --opaque --size 64x64 --point-size 3");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(RedAboveBlue(out)) << "the top of the facade is not at the top of the image";
  const Result bad = RunCandi("render " + dir.File("facade.ply") + " -o " + dir.File("bad.png") +
                              " --up 0,-1,0 --from 0,2,0");
  EXPECT_EQ(bad.code, 1) << bad.output;
  EXPECT_NE(bad.output.find("parallel"), std::string::npos) << bad.output;
  EXPECT_FALSE(FileExists(dir.File("bad.png")));
}

// A facade whose top is +x (a red band at x = +2, blue at x = -2, in the plane z = 0) and one
// COLMAP camera, rolled so that its image up is +x, looking along +z (a hand-written text model).
// --cameras takes up and side from the camera: red above blue.
TEST(RenderCli, CamerasOrientTheDefaultView) {
  TempDir dir;
  PointCloud c;
  c.schema.colors = true;
  c.SetSchema(c.schema);
  Rng rng(4);
  for (int i = 0; i < 20000; ++i) {
    const bool top = i % 2 == 0;
    c.positions.push_back(Eigen::Vector3d((top ? 2 : -2) + rng.Uniform(-0.5, 0.5), rng.Uniform(-4, 4),
                                          rng.Uniform(-0.1, 0.1)));
    c.colors.push_back(top ? Rgb8{255, 0, 0} : Rgb8{0, 0, 255});
  }
  c.Resize(c.positions.size());
  io::WritePointCloud(dir.File("facade.ply"), c);
  const std::string model = dir.File("sparse");
  std::filesystem::create_directories(model);
  WriteBytes(model + "/cameras.txt", "1 PINHOLE 100 100 50 50 50 50\n");
  // cam_from_world: a turn of -90 degrees about z, so the camera's down (+y) is world -x.
  WriteBytes(model + "/images.txt", "1 0.70710678118654757 0 0 -0.70710678118654757 0 0 -10 1 a.png\n\n");
  WriteBytes(model + "/points3D.txt", "");
  const std::string out = dir.File("cams.png");
  const Result r = RunCandi("render " + dir.File("facade.ply") + " -o " + out + " --cameras " + model +
                            " --opaque --size 64x64 --point-size 3");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(RedAboveBlue(out)) << "the camera's up is not the image's up";
  // A folder that is no model: exit 2, naming it.
  const Result bad = RunCandi("render " + dir.File("facade.ply") + " -o " + dir.File("bad.png") + " --cameras " +
                              dir.path());
  EXPECT_EQ(bad.code, 2) << bad.output;
  EXPECT_FALSE(FileExists(dir.File("bad.png")));
}

// Clipping: the red square (z = 95) cut away by a half-space, or kept alone by a box; in memory,
// streamed and from an archive. Bad clip options name themselves.
TEST(RenderCli, ClipPlaneAndClipBoxKeepOnlyTheirSide) {
  Scene s;
  const std::string archive = s.dir.File("both.archive");
  ASSERT_EQ(RunCandi("pack " + s.Inputs() + " -o " + archive).code, 0);
  for (const std::string& in : {s.Inputs() + " --mode memory", archive}) {  // stream mode: perspective only
    const std::string below = s.dir.File("below.png"), box = s.dir.File("box.png");
    Result r = RunCandi("render " + in + " --view " + s.view + " -L 8 --clip-plane 0,0,92,0,0,-1 -o " + below);
    ASSERT_EQ(r.code, 0) << r.output;
    const Image8 blue = io::ReadPng(below).image8;
    EXPECT_LT(MeanChannel(blue, 0), 1.0) << in;  // no red left
    EXPECT_GT(MeanChannel(blue, 2), 20.0) << in;
    EXPECT_NE(io::ReadPng(below).text.at("candi:clip").find("92"), std::string::npos);
    r = RunCandi("render " + in + " --view " + s.view + " -L 8 --clip-box 500000,4500000,94,500010,4500010,96 -o " + box);
    ASSERT_EQ(r.code, 0) << r.output;
    const Image8 red = io::ReadPng(box).image8;
    EXPECT_LT(MeanChannel(red, 2), 1.0) << in;
    EXPECT_GT(MeanChannel(red, 0), 20.0) << in;
  }
  for (const std::string bad : {"--clip-plane 0,0,92,0,0,0", "--clip-plane 1,2,3", "--clip-box 0,0,0,-1,1,1",
                                 "--clip-box 0,0,0,1,1,nan"}) {
    const Result r = RunCandi("render " + s.Inputs() + " -o " + s.dir.File("x.png") + " " + bad);
    EXPECT_EQ(r.code, 1) << bad;
    EXPECT_NE(r.output.find(bad.substr(0, bad.find(' '))), std::string::npos) << r.output;
    EXPECT_FALSE(FileExists(s.dir.File("x.png")));
  }
}

TEST(RenderCli, MergesInputsAndRecordsSeedAndRepeatLevel) {
  Scene s;
  const std::string out = s.dir.File("out.png");
  const Result r = RunCandi("render " + s.Inputs() + " -o " + out + " --view " + s.view +
                            " -L 16 --seed 5 --brightness none --png16 " + s.dir.File("out16.png"));
  ASSERT_EQ(r.code, 0) << r.output;
  const io::PngImage png = io::ReadPng(out);
  EXPECT_EQ(png.image8.width(), 40);
  EXPECT_EQ(png.text.at("candi:seed"), "5");
  EXPECT_EQ(png.text.at("candi:repeat_level"), "16");
  EXPECT_NE(png.text.at("candi:inputs").find("front.las"), std::string::npos);
  // 400 points/m^2 at 0.2 m pixels: 16 points per pixel, one per ensemble and layer. SPBR's law
  // gives red alpha = 1 - (1 - 1/1600)^1600 over blue seen through it.
  const double red = 1 - std::pow(1 - 1 / 1600.0, 1600.0);
  EXPECT_NEAR(MeanChannel(png.image8, 0), 255 * red, 255 * 0.03);
  EXPECT_NEAR(MeanChannel(png.image8, 2), 255 * (1 - red) * red, 255 * 0.03);
  const io::PngImage png16 = io::ReadPng(s.dir.File("out16.png"));
  EXPECT_EQ(png16.bit_depth, 16);
  EXPECT_NEAR(png16.image16.at(20, 20, 0) / 257.0, png.image8.at(20, 20, 0), 0.5001);
}

TEST(RenderCli, SameSeedSameBytesForOneAndTwoThreadsAndEitherMode) {
  Scene s;
  const std::string common = "render " + s.Inputs() + " --view " + s.view + " -L 8 ";
  ASSERT_EQ(RunCandi(common + "-o " + s.dir.File("a.png") + " --threads 1 --seed 3").code, 0);
  ASSERT_EQ(RunCandi(common + "-o " + s.dir.File("b.png") + " --threads 2 --seed 3").code, 0);
  EXPECT_EQ(ReadBytes(s.dir.File("a.png")), ReadBytes(s.dir.File("b.png")));
  ASSERT_EQ(RunCandi(common + "-o " + s.dir.File("c.png") + " --seed 4").code, 0);
  EXPECT_NE(ReadBytes(s.dir.File("a.png")), ReadBytes(s.dir.File("c.png")));
  // Streaming (perspective views only) is deterministic across thread counts and budgets too.
  const std::string stream = "render " + s.Inputs() + " --size 48x32 -L 8 --mode stream ";
  ASSERT_EQ(RunCandi(stream + "-o " + s.dir.File("s1.png") + " --threads 1").code, 0);
  const Result r = RunCandi(stream + "-o " + s.dir.File("s2.png") + " --threads 2 --memory-budget 0.05");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("pass(es)"), std::string::npos);
  EXPECT_EQ(ReadBytes(s.dir.File("s1.png")), ReadBytes(s.dir.File("s2.png")));
  EXPECT_EQ(io::ReadPng(s.dir.File("s1.png")).text.at("candi:mode"), "stream");
}

TEST(RenderCli, SavedViewRepeatsTheRenderExactly) {
  Scene s;
  const std::string common = "render " + s.Inputs() + " -L 4 --size 64x48 ";
  ASSERT_EQ(RunCandi(common + "-o " + s.dir.File("a.png") + " --save-view " + s.dir.File("v.json")).code, 0);
  const Result r = RunCandi(common + "-o " + s.dir.File("b.png") + " --view " + s.dir.File("v.json"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(io::ReadPng(s.dir.File("a.png")).image8.values(), io::ReadPng(s.dir.File("b.png")).image8.values());
}

TEST(RenderCli, BadViewFilesAreExitTwoNamingTheKeyAndPreviewRendersKEnsembles) {
  Scene s;
  WriteBytes(s.dir.File("bad.json"), R"({"projection": "orthographic", "eye": [1, 2], "width": 8})");
  Result r = RunCandi("render " + s.back + " -o " + s.dir.File("x.png") + " --view " + s.dir.File("bad.json"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("/eye"), std::string::npos) << r.output;
  WriteBytes(s.dir.File("typo.json"), R"({"projection": "orthographic", "ortho_heigth": 8})");
  r = RunCandi("render " + s.back + " -o " + s.dir.File("x.png") + " --view " + s.dir.File("typo.json"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("ortho_heigth"), std::string::npos) << r.output;
  // 2^32 + 1 used to wrap to a 1-pixel width.
  WriteBytes(s.dir.File("wide.json"), R"({"projection": "orthographic", "width": 4294967297, "height": 8})");
  r = RunCandi("render " + s.back + " -o " + s.dir.File("x.png") + " --view " + s.dir.File("wide.json"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("/width: out of range"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(s.dir.File("x.png")));
  r = RunCandi("render " + s.Inputs() + " -o " + s.dir.File("p.png") + " --view " + s.view + " -L 50 --preview 3");
  ASSERT_EQ(r.code, 0) << r.output;
  const io::PngImage png = io::ReadPng(s.dir.File("p.png"));
  EXPECT_EQ(png.text.at("candi:ensembles"), "3");
  EXPECT_EQ(png.text.at("candi:repeat_level"), "50");
}

TEST(RenderCli, PerInputAlphaZeroHidesALayerAndOneMakesItOpaque) {
  Scene s;
  const std::string common = "render " + s.Inputs() + " --view " + s.view + " -L 32 --brightness none ";
  // The red top layer at alpha 0 vanishes: pure blue.
  Result r = RunCandi(common + "-o " + s.dir.File("a.png") + " --alpha 1,0");
  ASSERT_EQ(r.code, 0) << r.output;
  Image8 image = io::ReadPng(s.dir.File("a.png")).image8;
  EXPECT_EQ(MeanChannel(image, 0), 0.0);
  EXPECT_GT(MeanChannel(image, 2), 250);
  // Red at alpha 1 hides the blue layer completely.
  r = RunCandi(common + "-o " + s.dir.File("b.png") + " --alpha 0.5,1");
  ASSERT_EQ(r.code, 0) << r.output;
  image = io::ReadPng(s.dir.File("b.png")).image8;
  EXPECT_GT(MeanChannel(image, 0), 250);
  EXPECT_LT(MeanChannel(image, 2), 1.0);
  // Red at 0.5 over opaque blue: about half and half.
  r = RunCandi(common + "-o " + s.dir.File("c.png") + " --alpha 1,0.5");
  ASSERT_EQ(r.code, 0) << r.output;
  image = io::ReadPng(s.dir.File("c.png")).image8;
  EXPECT_NEAR(MeanChannel(image, 0) / 255, 0.5, 0.06);
  EXPECT_NEAR(MeanChannel(image, 2) / 255, 0.5, 0.06);
  // Everything at alpha 0: the background only, said plainly.
  r = RunCandi(common + "-o " + s.dir.File("d.png") + " --alpha 0 --background 10,20,30");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("background"), std::string::npos) << r.output;
  image = io::ReadPng(s.dir.File("d.png")).image8;
  EXPECT_EQ(MeanChannel(image, 1), 20.0);
}

TEST(RenderCli, EmptyNanAndMissingInputsAreExitTwoNamingTheCause) {
  Scene s;
  WriteBytes(s.dir.File("empty.ply"), "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\n"
                                      "property float y\nproperty float z\nend_header\n");
  WriteBytes(s.dir.File("old.png"), "earlier output");
  Result r = RunCandi("render " + s.dir.File("empty.ply") + " -o " + s.dir.File("old.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("nothing to render"), std::string::npos) << r.output;
  EXPECT_EQ(ReadBytes(s.dir.File("old.png")), "earlier output");
  WriteBytes(s.dir.File("nan.xyz"), "1 2 3\nnan 2 3\n");
  r = RunCandi("render " + s.dir.File("nan.xyz") + " -o " + s.dir.File("old.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("nan.xyz"), std::string::npos) << r.output;
  EXPECT_EQ(ReadBytes(s.dir.File("old.png")), "earlier output");
  r = RunCandi("render " + s.back + " " + s.dir.File("missing.ply") + " -o " + s.dir.File("x.png"));
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("missing.ply"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(s.dir.File("x.png")));
  r = RunCandi("render " + s.back + " -o " + s.dir.File("no/dir/x.png") + " -L 2");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("no/dir"), std::string::npos) << r.output;
}

TEST(RenderCli, BadOptionValuesAreExitOneNamingTheOption) {
  Scene s;
  const std::string common = "render " + s.back + " -o " + s.dir.File("x.png") + " ";
  const std::pair<const char*, const char*> cases[] = {
      {"--size 0x10", "--size"},           {"--size 10", "--size"},
      {"--background 1,2", "--background"}, {"--background 1,2,300", "--background"},
      {"--brightness -1", "--brightness"}, {"--alpha 1.5", "--alpha"},
      {"--alpha 0.5,0.5", "--alpha"},      {"-L 0", "--repeat-level"},
      {"--mode fast", "--mode"},           {"--opaque --alpha 0.5", "--opaque"},
      {"--point-size 0.5", "point_size"},  {"--threads -1", "--threads"}};
  for (const auto& [option, named] : cases) {
    const Result r = RunCandi(common + option);
    EXPECT_EQ(r.code, 1) << option << "\n" << r.output;
    EXPECT_NE(r.output.find(named), std::string::npos) << option << "\n" << r.output;
  }
  const Result r = RunCandi(common + "--mode stream --memory-budget 0.001 --size 100x100");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_NE(r.output.find("memory_budget"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(s.dir.File("x.png")));
}

}  // namespace
}  // namespace candi::testing

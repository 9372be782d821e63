// End-to-end tests of `candi opacity`: exit codes, messages, the output's field and comment.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "core/rng.h"
#include "io/point_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

using Result = CommandResult;

// 20k points, uniform on a 5 x 5 m square at survey coordinates (800 points/m^2), with colour.
void WritePlane(const std::string& path) {
  PointCloud c;
  c.schema.colors = true;
  c.SetSchema(c.schema);
  c.Resize(20000);
  Rng rng(3);
  for (size_t i = 0; i < c.size(); ++i) {
    c.positions[i] =
        Eigen::Vector3d(500000.0 + rng.Uniform(0, 5), 4500000.0 + rng.Uniform(0, 5), 90);
    c.colors[i] = {static_cast<uint8_t>(i), 100, 200};
  }
  io::WritePointCloud(path, c);
}

const char kGood[] = " --alpha 0.5 --repeat-level 20 --image-size 256";

TEST(OpacityCli, WritesTheMultiplicityFieldCommentAndSummary) {
  TempDir dir;
  WritePlane(dir.File("in.las"));
  const Result r = RunCandi("opacity " + dir.File("in.las") + " " + dir.File("out.ply") + kGood);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.out.find("points in        20000"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("predicted alpha"), std::string::npos) << r.out;
  const std::string bytes = ReadBytes(dir.File("out.ply"));
  EXPECT_NE(bytes.find("property float scalar_spbr_multiplicity"), std::string::npos);
  EXPECT_NE(bytes.find("comment candi_opacity alpha=0.5 repeat_level=20 pixel_size="),
            std::string::npos);
  const PointCloud out = io::ReadPointCloud(dir.File("out.ply"));
  const ScalarField* m = out.FindScalar("spbr_multiplicity");
  ASSERT_NE(m, nullptr);
  ASSERT_GT(out.size(), 0u);
  EXPECT_TRUE(out.schema.colors);
  for (size_t i = 0; i < out.size(); ++i) {
    ASSERT_GE(m->Get(i), 1.0);
    ASSERT_LE(m->Get(i), 20.0);
    ASSERT_EQ(m->Get(i), std::floor(m->Get(i)));
  }
  EXPECT_GT(out.WorldPosition(0).x(), 499999.0) << "world coordinates kept";
  // The output can be adjusted again (its multiplicities count as points), voxel method too.
  const Result again = RunCandi("-q opacity " + dir.File("out.ply") + " " + dir.File("again.ply") +
                                kGood + " --method voxel --seed 7");
  EXPECT_EQ(again.code, 0) << again.output;
}

// `candi render FILE` draws a point as often as the file's multiplicity field says: with every
// multiplicity 0 nothing is drawn (and it says so); without the field every point is.
TEST(OpacityCli, RenderDrawsAFilesPointsAsOftenAsItsMultiplicitiesSay) {
  TempDir dir;
  WritePlane(dir.File("plain.ply"));
  PointCloud c = io::ReadPointCloud(dir.File("plain.ply"));
  c.AddScalarField("spbr_multiplicity");  // zero-filled
  io::WritePointCloud(dir.File("none.ply"), c);
  const Result none = RunCandi("render " + dir.File("none.ply") + " -o " + dir.File("none.png") + " --size 64x48");
  ASSERT_EQ(none.code, 0) << none.output;
  EXPECT_NE(none.output.find("every point was removed"), std::string::npos) << none.output;
  const Result plain = RunCandi("render " + dir.File("plain.ply") + " -o " + dir.File("plain.png") + " --size 64x48");
  ASSERT_EQ(plain.code, 0) << plain.output;
  EXPECT_EQ(plain.output.find("every point was removed"), std::string::npos) << plain.output;
}

TEST(OpacityCli, MissingInputIsExitTwoNamingIt) {
  TempDir dir;
  const Result r = RunCandi("opacity " + dir.File("nope.ply") + " " + dir.File("out.ply") + kGood);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find(dir.File("nope.ply")), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("out.ply")));
}

TEST(OpacityCli, UnwritableOutputFolderIsExitTwo) {
  TempDir dir;
  WritePlane(dir.File("in.ply"));
  const Result r =
      RunCandi("opacity " + dir.File("in.ply") + " " + dir.File("no/such/dir/out.ply") + kGood);
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("no/such/dir"), std::string::npos) << r.output;
  EXPECT_FALSE(FileExists(dir.File("no")));
}

TEST(OpacityCli, BadValuesAreExitOneBeforeAnyReading) {
  TempDir dir;
  const std::string files = "opacity " + dir.File("missing.ply") + " " + dir.File("out.ply");
  Result r = RunCandi(files + " --alpha 1.5 --repeat-level 20 --image-size 256");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("OpacityOptions::alpha = 1.5; must be in [0, 1]"), std::string::npos)
      << r.output;
  r = RunCandi(files + " --alpha 0.5 --repeat-level 0 --image-size 256");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("repeat_level = 0"), std::string::npos) << r.output;
  r = RunCandi(files + " --alpha 0.5 --repeat-level 20 --image-size 256 --pixel-size 0.01");
  EXPECT_EQ(r.code, 1);
  EXPECT_NE(r.output.find("exactly one"), std::string::npos) << r.output;
  r = RunCandi(files + " --alpha 0.5 --repeat-level 20");
  EXPECT_EQ(r.code, 1) << "neither --image-size nor --pixel-size";
  EXPECT_NE(r.output.find("exactly one"), std::string::npos) << r.output;
  EXPECT_EQ(RunCandi(files + kGood + " --neighbours 16 --radius 0.1").code, 1);
  EXPECT_EQ(RunCandi(files + kGood + " --method octree").code, 1);
  EXPECT_EQ(RunCandi(files + " --repeat-level 20 --image-size 256").code, 1) << "--alpha required";
}

}  // namespace
}  // namespace candi::testing

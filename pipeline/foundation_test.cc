#include "pipeline/foundation.h"

#include <gtest/gtest.h>

#include "core/check.h"
#include "io/layer_clouds.h"
#include "io/point_io.h"
#include "tests/util/dxf_text.h"
#include "tests/util/test_util.h"

namespace candi::pipeline {
namespace {

using testing::DxfText;
using testing::TempDir;
using V = Eigen::Vector2d;

std::string Drawing(const TempDir& dir) {
  DxfText text;
  text.Lines("A", {V(-30, -5), V(-12, 3), V(2, 8), V(15, 2), V(40, -6)});
  text.Lines("B", {V(-20, -4), V(0, 4), V(20, -4)});  // symmetric: swept
  testing::WriteBytes(dir.File("f.dxf"), text.str());
  return dir.File("f.dxf");
}

FoundationPointsOptions Small() {
  FoundationPointsOptions o;
  o.surface.profile.samples_per_side = 40;
  o.surface.revolve.angular_steps = 16;
  o.sample.count = 5000;
  return o;
}

TEST(FoundationPointsOptions, NoDefaultAmountAndBadValuesAreNamed) {
  // As SurfaceSampleOptions': no default amount of points; the callers choose count or density.
  FoundationPointsOptions o;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o.sample.density = kDefaultFoundationDensity;
  EXPECT_NO_THROW(o.Check());
  o.surface.revolve.angular_steps = 1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = FoundationPointsOptions();
  o.sample.density = -1;
  try {
    o.Check();
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("density = -1"), std::string::npos) << e.what();
  }
}

TEST(DigitizeFoundation, EveryLayerSurfacedAndSampledByArea) {
  TempDir dir;
  const FoundationPoints f = DigitizeFoundation(Small(), Drawing(dir));
  ASSERT_EQ(f.surfaces.size(), 2u);
  EXPECT_EQ(f.Names(), (std::vector<std::string>{"A", "B"}));
  EXPECT_EQ(f.surfaces[1].mode, mesh::RevolveMode::kSweep);
  uint64_t total = 0;
  for (size_t k = 0; k < 2; ++k) {
    total += f.clouds[k].size();
    EXPECT_TRUE(f.clouds[k].schema.layers && f.clouds[k].schema.colors && f.clouds[k].schema.normals);
    EXPECT_EQ(f.clouds[k].layers.front(), k);
    EXPECT_GT(f.areas[k], 0);
  }
  EXPECT_EQ(total, 5000u);  // split by area, exactly
  // The larger surface gets more points.
  EXPECT_EQ(f.areas[0] > f.areas[1], f.clouds[0].size() > f.clouds[1].size());
}

// What a build keeps in memory is what `candi foundation` writes and a reader gives back.
TEST(DigitizeFoundation, MergedEqualsTheWrittenFileReadBack) {
  TempDir dir;
  const FoundationPoints f = DigitizeFoundation(Small(), Drawing(dir));
  io::WriteLayerClouds(dir.File("f.ply"), f.clouds, f.Names());
  const PointCloud back = io::ReadPointCloud(dir.File("f.ply"));
  const PointCloud merged = f.Merged();
  ASSERT_EQ(merged.size(), back.size());
  EXPECT_EQ(merged.schema, back.schema);
  EXPECT_EQ(merged.frame, back.frame);
  EXPECT_EQ(merged.positions, back.positions);
  EXPECT_EQ(merged.normals, back.normals);
  EXPECT_EQ(merged.layers, back.layers);
  for (size_t i = 0; i < merged.size(); ++i) ASSERT_EQ(merged.colors[i], back.colors[i]) << i;
  EXPECT_EQ(io::ReadLayerNames(merged.meta), io::ReadLayerNames(back.meta));
  EXPECT_EQ(io::ReadLayerNames(merged.meta).at(1), "B");
}

TEST(DigitizeFoundation, SameSeedSameBytesAnyThreadCount) {
  TempDir dir;
  FoundationPointsOptions o = Small();
  o.sample.threads = 1;
  const PointCloud one = DigitizeFoundation(o, Drawing(dir)).Merged();
  o.sample.threads = 2;
  const PointCloud two = DigitizeFoundation(o, Drawing(dir)).Merged();
  EXPECT_EQ(one.positions, two.positions);
  o.sample.seed = 2;
  EXPECT_NE(DigitizeFoundation(o, Drawing(dir)).Merged().positions, one.positions);
}

TEST(DigitizeFoundation, BadDrawingsAndLayersAreNamed) {
  TempDir dir;
  FoundationPointsOptions o = Small();
  o.layers = {"Z"};
  try {
    DigitizeFoundation(o, Drawing(dir));
    ADD_FAILURE();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("f.dxf"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'Z'"), std::string::npos) << e.what();
  }
  testing::WriteBytes(dir.File("empty.dxf"), DxfText().str());
  EXPECT_THROW(DigitizeFoundation(Small(), dir.File("empty.dxf")), InputError);
  EXPECT_THROW(DigitizeFoundation(Small(), dir.File("missing.dxf")), InputError);
}

}  // namespace
}  // namespace candi::pipeline

#include "pipeline/section.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "core/base64.h"
#include "core/check.h"
#include "core/polyline.h"
#include "core/rng.h"
#include "io/layer_clouds.h"
#include "io/point_io.h"
#include "render/archive_pack.h"
#include "tests/util/option_check.h"
#include "tests/util/test_util.h"

namespace candi::pipeline {
namespace {

using testing::ExpectEachBreakRejected;
using testing::TempDir;

// Two walls 5 m apart (x = 0: layer "west", x = 5: layer "east"), 10 m long and 3 m high, at
// survey coordinates.
const Eigen::Vector3d kOrigin(400000, 9000000, 100);

PointCloud Wall(double x, int layer, uint64_t seed) {
  PointCloud c;
  c.schema.colors = true;
  c.schema.layers = true;
  c.SetSchema(c.schema);
  c.frame.origin = kOrigin;
  Rng rng(seed);
  for (int i = 0; i < 20000; ++i) {
    c.positions.push_back({x, rng.Uniform(0, 10), rng.Uniform(0, 3)});
    c.colors.push_back({100, 100, 100});
    c.layers.push_back(static_cast<uint16_t>(layer));
  }
  return c;
}

std::string WriteWalls(const TempDir& dir) {
  io::WriteLayerClouds(dir.File("walls.ply"), {Wall(0, 0, 1), Wall(5, 1, 2)}, {"west", "east"});
  return dir.File("walls.ply");
}

// A plan cut at 1.5 m above the walls' foot.
section::SectionPath PlanCut() { return section::SectionPath::Plane(kOrigin + Eigen::Vector3d(0, 0, 1.5), {0, 0, 1}, 0.1); }

TEST(SectionOptions, DefaultsPassAndRulesAreChecked) {
  ExpectEachBreakRejected<SectionOptions>({}, {
      [](SectionOptions& o) { o.opacity = 0; },
      [](SectionOptions& o) { o.width = 8; },
  });
}

TEST(CutSection, ALineAlongEachWallInSurveyCoordinates) {
  TempDir dir;
  const SectionCut cut = CutSection(SectionOptions(), {WriteWalls(dir)}, PlanCut(), ClipRegion());
  ASSERT_EQ(cut.layers.size(), 2u);
  EXPECT_EQ(cut.layers[0].name, "west");
  EXPECT_EQ(cut.layers[1].name, "east");
  EXPECT_FALSE(cut.archive);
  EXPECT_EQ(cut.points_read, 40000u);
  for (const section::SectionLayerResult& l : cut.layers) {
    EXPECT_GT(l.points, 300u);
    ASSERT_FALSE(l.lines.empty()) << l.name;
    EXPECT_NEAR(l.length, 10.0, 0.5) << l.name;
    // A plan cut draws world x, y: the wall's easting, to the millimetre at 4e5 m.
    const double x = l.name == "west" ? kOrigin.x() : kOrigin.x() + 5;
    for (const Eigen::Vector2d& p : l.lines[0].points) EXPECT_NEAR(p.x(), x, 1e-3) << l.name;
  }
  EXPECT_EQ(cut.Points(), cut.layers[0].points + cut.layers[1].points);
  const nlohmann::json summary = nlohmann::json::parse(cut.summary);
  EXPECT_EQ(summary.at("points").get<uint64_t>(), cut.Points());
  EXPECT_EQ(summary.at("layers").size(), 2u);
  EXPECT_EQ(cut.image.width(), cut.window.width);
}

TEST(CutSection, OnlyTheLayersAskedForAndTheClipping) {
  TempDir dir;
  SectionOptions o;
  o.layers = {"east"};
  const SectionCut east = CutSection(o, {WriteWalls(dir)}, PlanCut(), ClipRegion());
  ASSERT_EQ(east.layers.size(), 1u);
  EXPECT_EQ(east.layers[0].name, "east");
  o.layers = {"north"};
  EXPECT_THROW(CutSection(o, {WriteWalls(dir)}, PlanCut(), ClipRegion()), std::invalid_argument);
  // A clip box around the west wall only.
  const ClipRegion west = ClipRegion::Box({kOrigin + Eigen::Vector3d(-1, -1, -1), kOrigin + Eigen::Vector3d(1, 11, 4)});
  const SectionCut clipped = CutSection(SectionOptions(), {WriteWalls(dir)}, PlanCut(), west);
  EXPECT_GT(clipped.layers[0].points, 0u);
  EXPECT_EQ(clipped.layers[1].points, 0u);
}

TEST(WriteSection, TheFiveFiles) {
  TempDir dir;
  const section::SectionPath path = PlanCut();
  const SectionCut cut = CutSection(SectionOptions(), {WriteWalls(dir)}, path, ClipRegion());
  WriteSection(cut, path, dir.File("out"));
  for (const char* f : {"section.png", "section.dxf", "section.csv", "section.svg", "section.json"}) {
    EXPECT_TRUE(testing::FileExists(dir.File(std::string("out/") + f))) << f;
  }
  EXPECT_EQ(ReadFileToString(dir.File("out/section.json")), cut.summary);
  EXPECT_EQ(io::ReadPng(dir.File("out/section.png")).text.at("candi:section"), cut.describe);
}

SectionOptions OneThread() {
  SectionOptions o;
  o.threads = 1;
  return o;
}

// The viewer's export sends what `candi section` writes: the same DXF, SVG, CSV and PNG bytes.
TEST(ExportViewerSection, TheBytesCandiSectionWrites) {
  TempDir dir;
  WriteWalls(dir);
  io::WritePointCloud(dir.File("west.ply"), Wall(0, 0, 1));
  io::WritePointCloud(dir.File("east.ply"), Wall(5, 1, 2));
  render::PackFiles(render::PackOptions(), {dir.File("west.ply"), dir.File("east.ply")}, "", dir.File("archive"));
  const render::Archive archive(dir.File("archive"));
  view::SectionRequest request;
  request.point = kOrigin + Eigen::Vector3d(0, 0, 1.5);
  request.normal = Eigen::Vector3d::UnitZ();
  request.thickness = 0.1;
  view::ViewState state;
  const nlohmann::json reply =
      nlohmann::json::parse(ExportViewerSection(dir.File("archive"), archive.manifest(), OneThread(), 7, request, state));
  EXPECT_EQ(reply.at("type"), "section");
  EXPECT_EQ(reply.at("seq"), 7);

  const section::SectionPath path = section::SectionPath::Plane(request.point, request.normal, request.thickness);
  SectionOptions o;
  o.threads = 1;
  WriteSection(CutSection(o, {dir.File("archive")}, path, ClipRegion()), path, dir.File("files"));
  EXPECT_EQ(reply.at("dxf").get<std::string>(), ReadFileToString(dir.File("files/section.dxf")));
  EXPECT_EQ(reply.at("svg").get<std::string>(), ReadFileToString(dir.File("files/section.svg")));
  EXPECT_EQ(reply.at("csv").get<std::string>(), ReadFileToString(dir.File("files/section.csv")));
  EXPECT_EQ(reply.at("png_base64").get<std::string>(), Base64(ReadFileToString(dir.File("files/section.png"))));
  EXPECT_EQ(reply.at("summary").at("points"), nlohmann::json::parse(ReadFileToString(dir.File("files/section.json"))).at("points"));
  // The page's shown layers only; every layer hidden is refused.
  state.settings.layer_fraction = {0, 1};
  const nlohmann::json east =
      nlohmann::json::parse(ExportViewerSection(dir.File("archive"), archive.manifest(), OneThread(), 8, request, state));
  EXPECT_EQ(east.at("summary").at("layers").size(), 1u);
  state.settings.layer_fraction = {0, 0};
  EXPECT_THROW(ExportViewerSection(dir.File("archive"), archive.manifest(), OneThread(), 9, request, state), std::invalid_argument);
}

// The viewer's bounds on an export: a slab of more points than max_points is refused while it is
// read (from an archive and from point files), and the checkpoint's exception aborts the cut.
TEST(CutSection, MaxPointsAndCheckpointBoundTheWork) {
  TempDir dir;
  io::WritePointCloud(dir.File("west.ply"), Wall(0, 0, 1));
  io::WritePointCloud(dir.File("east.ply"), Wall(5, 1, 2));
  render::PackFiles(render::PackOptions(), {dir.File("west.ply"), dir.File("east.ply")}, "", dir.File("archive"));
  // A horizontal slab 1 m thick holds a third of each wall: ~13,300 points.
  const section::SectionPath path = section::SectionPath::Plane(kOrigin + Eigen::Vector3d(0, 0, 1.5),
                                                                Eigen::Vector3d::UnitZ(), 1.0);
  SectionOptions o = OneThread();
  const uint64_t all = CutSection(o, {dir.File("archive")}, path, ClipRegion()).Points();
  ASSERT_GT(all, 10000u);
  o.max_points = all;  // exactly the slab: allowed
  EXPECT_EQ(CutSection(o, {dir.File("archive")}, path, ClipRegion()).Points(), all);
  o.max_points = all - 1;
  for (const std::string& input : {dir.File("archive"), dir.File("west.ply")}) {
    if (input != dir.File("archive")) o.max_points = all / 4;  // one wall holds about half
    try {
      CutSection(o, {input}, path, ClipRegion());
      ADD_FAILURE() << input << ": no error";
    } catch (const std::length_error& e) {
      EXPECT_NE(std::string(e.what()).find("more than " + std::to_string(o.max_points) + " points"), std::string::npos)
          << e.what();
    }
  }
  struct Stop {};
  int calls = 0;
  o.max_points = 0;
  o.checkpoint = [&] {
    if (++calls == 2) throw Stop{};
  };
  EXPECT_THROW(CutSection(o, {dir.File("archive")}, path, ClipRegion()), Stop);
  EXPECT_EQ(calls, 2);
}

}  // namespace
}  // namespace candi::pipeline

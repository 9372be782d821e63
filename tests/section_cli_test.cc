// End-to-end tests of `candi section`: the foundation's section at the drawing's plane gives the
// drawing's profiles back (DXF read with candi's own reader), a swept layer's section at another
// angle gives the same profile, survey coordinates keep their millimetres, archives are read only
// where the slab crosses them, and degenerate input gives a clear error or an empty, labelled
// output.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "core/polyline.h"
#include "core/rng.h"
#include "io/point_io.h"
#include "mesh/dxf_import.h"
#include "mesh/foundation.h"
#include "mesh/profile.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

using Result = CommandResult;

const std::string kDrawing = "examples/borobudur/foundation.dxf";  // tests run in the source directory

// Distance from p to the polyline through `line`.
// The layer's profile as the foundation path builds it from the drawing (both sides joined, in
// drawing coordinates): the curve its surface passes through at the drawing's plane.
std::vector<Eigen::Vector2d> DrawingProfile(const std::string& layer) {
  const mesh::FoundationOptions o;
  const mesh::DxfDrawing drawing = mesh::ReadDxf(o.dxf, kDrawing);
  const mesh::Profile p = mesh::BuildProfile(o.profile, mesh::LayerSection(o, drawing, layer), {kDrawing, layer});
  std::vector<Eigen::Vector2d> out;
  for (auto it = p.left.rbegin(); it != p.left.rend(); ++it) out.push_back(*it + p.origin);
  for (size_t i = 1; i < p.right.size(); ++i) out.push_back(p.right[i] + p.origin);
  return out;
}

struct Deviation {
  double mean = 0, max = 0, length = 0;
  size_t vertices = 0;
  Eigen::Vector2d worst = Eigen::Vector2d::Zero();  // where the largest deviation is
};

// The section lines of `layer` in a DXF written by candi section, against `reference`.
Deviation Compare(const mesh::DxfDrawing& section, const std::string& layer, const std::vector<Eigen::Vector2d>& reference) {
  Deviation d;
  const auto it = section.layers.find(layer);
  if (it == section.layers.end()) return d;
  for (const Polyline2& line : it->second) {
    for (size_t i = 0; i < line.points.size(); ++i) {
      const double e = DistanceToPolyline(line.points[i], reference);
      d.mean += e;
      if (e > d.max) d.max = e, d.worst = line.points[i];
      ++d.vertices;
      if (i > 0) d.length += (line.points[i] - line.points[i - 1]).norm();
    }
  }
  if (d.vertices) d.mean /= d.vertices;
  return d;
}

double Length(const std::vector<Eigen::Vector2d>& line) {
  double l = 0;
  for (size_t i = 1; i < line.size(); ++i) l += (line[i] - line[i - 1]).norm();
  return l;
}

class FoundationSection : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    const Result r = RunCandi("foundation " + kDrawing + " -o " + dir_->File("foundation.ply"));
    ASSERT_EQ(r.code, 0) << r.output;
  }
  static void TearDownTestSuite() { delete dir_; }
  static TempDir* dir_;
};
TempDir* FoundationSection::dir_ = nullptr;

// The foundation's layers were built from the drawing: their section at the drawing's plane
// (world y = 0) must give the drawing's profiles back, at the default density.
TEST_F(FoundationSection, AtTheDrawingsPlaneMatchesTheDrawing) {
  const std::string out = dir_->File("y0");
  const Result r = RunCandi("section " + dir_->File("foundation.ply") + " --plane 0,0,0,0,1,0 --thickness 0.1 -o " + out);
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* f : {"section.png", "section.dxf", "section.csv", "section.svg", "section.json"}) {
    EXPECT_TRUE(FileExists(out + "/" + f)) << f;
  }
  const mesh::DxfDrawing section = mesh::ReadDxf(mesh::DxfReadOptions{}, out + "/section.dxf");
  EXPECT_EQ(section.unit_name, "metre");
  for (const std::string layer : {"A", "B", "C", "D"}) {
    const std::vector<Eigen::Vector2d> reference = DrawingProfile(layer);
    const Deviation d = Compare(section, layer, reference);
    std::printf("layer %s: %zu vertices, mean deviation %.2f mm, max %.2f mm (at %.3f, %.3f), %.1f of %.1f m covered\n",
                layer.c_str(), d.vertices, 1e3 * d.mean, 1e3 * d.max, d.worst.x(), d.worst.y(), d.length,
                Length(reference));
    ASSERT_GT(d.vertices, 100u) << layer;
    EXPECT_LE(d.mean, 0.005) << layer;
    EXPECT_LE(d.max, 0.02) << layer;
    EXPECT_GE(d.length, 0.97 * Length(reference)) << layer << ": the lines must cover the profile";
  }
}

// Layer D is symmetric and swept: a vertical section through its axis at any angle is its profile.
TEST_F(FoundationSection, ASweptLayerGivesTheSameProfileAtAnotherAngle) {
  const std::string out = dir_->File("a37");
  const double a = 37 * M_PI / 180;
  char plane[128];
  std::snprintf(plane, sizeof(plane), "0,0,0,%.17g,%.17g,0", -std::sin(a), std::cos(a));
  const Result r = RunCandi("section " + dir_->File("foundation.ply") + " --plane " + plane +
                            " --thickness 0.1 --layers D -o " + out);
  ASSERT_EQ(r.code, 0) << r.output;
  const mesh::DxfDrawing section = mesh::ReadDxf(mesh::DxfReadOptions{}, out + "/section.dxf");
  EXPECT_EQ(section.layers.count("A"), 0u) << "--layers D";
  const std::vector<Eigen::Vector2d> reference = DrawingProfile("D");
  const Deviation d = Compare(section, "D", reference);
  std::printf("layer D at 37 degrees: mean deviation %.2f mm, max %.2f mm\n", 1e3 * d.mean, 1e3 * d.max);
  ASSERT_GT(d.vertices, 100u);
  EXPECT_LE(d.mean, 0.005);
  EXPECT_LE(d.max, 0.02);
  EXPECT_GE(d.length, 0.97 * Length(reference));
}

// From an archive: only the chunks the slab crosses are read, and the lines agree with the point
// file's within the archive's quantization.
TEST_F(FoundationSection, FromAnArchiveReadsOnlyTheCrossedChunks) {
  const std::string archive = dir_->File("foundation.archive");
  Result r = RunCandi("pack " + dir_->File("foundation.ply") + " -o " + archive);
  ASSERT_EQ(r.code, 0) << r.output;
  r = RunCandi("section " + archive + " --plane 0,0,0,0,1,0 --thickness 0.1 -o " + dir_->File("arc"));
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json j = nlohmann::json::parse(ReadBytes(dir_->File("arc/section.json")));
  const uint64_t read = j.at("chunks_read"), chunks = j.at("chunks");
  std::printf("archive: read %llu of %llu chunks\n", static_cast<unsigned long long>(read),
              static_cast<unsigned long long>(chunks));
  EXPECT_GT(read, 0u);
  EXPECT_LT(read, chunks * 3 / 4);
  // The archive holds the layers as one (the file); its lines match the union of the profiles.
  const mesh::DxfDrawing section = mesh::ReadDxf(mesh::DxfReadOptions{}, dir_->File("arc/section.dxf"));
  ASSERT_EQ(section.layers.size(), 1u);
  std::vector<std::vector<Eigen::Vector2d>> profiles;
  for (const std::string layer : {"A", "B", "C", "D"}) profiles.push_back(DrawingProfile(layer));
  double mean = 0, worst = 0;
  size_t n = 0;
  for (const auto& line : section.layers.begin()->second) {
    for (const auto& v : line.points) {
      double best = 1e300;
      for (const auto& p : profiles) best = std::min(best, DistanceToPolyline(v, p));
      mean += best, worst = std::max(worst, best), ++n;
    }
  }
  ASSERT_GT(n, 100u);
  EXPECT_LE(mean / n, 0.005);
  EXPECT_LE(worst, 0.05);
}

// A column of radius 0.5 m standing at survey coordinates (1e6-1e7 m): a plan cut gives a closed
// circle in survey coordinates, with millimetre precision in the DXF.
TEST(SectionCli, SurveyCoordinatesKeepMillimetresInTheDxf) {
  TempDir dir;
  PointCloud c;
  c.frame.origin = Eigen::Vector3d(712000, 9162000, 200);
  const Eigen::Vector2d centre(712345.6789, 9162345.4321);
  Rng rng(5);
  for (int i = 0; i < 200000; ++i) {
    const double t = rng.Uniform(0, 2 * M_PI), z = rng.Uniform(250, 254);
    c.positions.push_back(Eigen::Vector3d(centre.x() + 0.5 * std::cos(t), centre.y() + 0.5 * std::sin(t), z) - c.frame.origin);
  }
  io::WritePointCloud(dir.File("column.ply"), c);
  const Result r = RunCandi("section " + dir.File("column.ply") + " --plane 712345,9162345,252,0,0,1 --thickness 0.05 -o " +
                            dir.File("plan"));
  ASSERT_EQ(r.code, 0) << r.output;
  const mesh::DxfDrawing section = mesh::ReadDxf(mesh::DxfReadOptions{}, dir.File("plan/section.dxf"));
  ASSERT_EQ(section.layers.count("column"), 1u);
  const auto& lines = section.layers.at("column");
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_TRUE(lines[0].closed);
  double mean = 0, worst = 0;
  for (const Eigen::Vector2d& v : lines[0].points) {
    const double e = std::abs((v - centre).norm() - 0.5);
    mean += e;
    worst = std::max(worst, e);
  }
  mean /= lines[0].points.size();
  std::printf("survey-scale column: %zu vertices, radius error mean %.3f mm, max %.3f mm\n", lines[0].points.size(),
              1e3 * mean, 1e3 * worst);
  EXPECT_LE(mean, 0.001);
  EXPECT_LE(worst, 0.003);
}

TEST(SectionCli, DegenerateInputIsAClearErrorOrAnEmptyLabelledOutput) {
  TempDir dir;
  PointCloud flat;
  Rng rng(3);
  for (int i = 0; i < 20000; ++i) flat.positions.push_back({rng.Uniform(0, 10), rng.Uniform(0, 10), 5.0});
  io::WritePointCloud(dir.File("floor.ply"), flat);
  const std::string floor = dir.File("floor.ply");
  // Thickness 0 or negative, a path of one distinct vertex: errors naming the option, nothing written.
  for (const std::string bad : {"--plane 0,0,5,0,0,1 --thickness 0", "--plane 0,0,5,0,0,1 --thickness -1",
                                "--path 1,1,1,1,1,1 --thickness 0.1", "--plane 0,0,5,0,0,0 --thickness 0.1",
                                "--plane 0,0,5,0,0,1 --through 0,0,1,1 --thickness 0.1"}) {
    const Result r = RunCandi("section " + floor + " " + bad + " -o " + dir.File("bad"));
    EXPECT_EQ(r.code, 1) << bad << "\n" << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.File("bad"))) << bad;
  }
  EXPECT_NE(RunCandi("section " + floor + " --plane 0,0,5,0,0,1 --thickness 0 -o " + dir.File("bad")).output.find("--thickness"),
            std::string::npos);
  EXPECT_NE(RunCandi("section " + floor + " --path 1,1,1,1,1,1 --thickness 0.1 -o " + dir.File("bad")).output.find("3 vertices, 1 distinct"),
            std::string::npos);
  // A slab with no points: every output, labelled empty.
  Result r = RunCandi("section " + floor + " --plane 0,0,50,0,0,1 --thickness 0.1 -o " + dir.File("empty"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("no points within the slab"), std::string::npos) << r.output;
  nlohmann::json j = nlohmann::json::parse(ReadBytes(dir.File("empty/section.json")));
  EXPECT_EQ(j.at("points"), 0);
  EXPECT_EQ(j.at("message"), "no points within the slab");
  EXPECT_NE(ReadBytes(dir.File("empty/section.dxf")).find("floor"), std::string::npos) << "the layer is labelled";
  EXPECT_TRUE(FileExists(dir.File("empty/section.png")));
  // A plane parallel to the flat layer, within it: an area, not a line; said so, no lines.
  r = RunCandi("section " + floor + " --plane 0,0,5,0,0,1 --thickness 0.1 -o " + dir.File("inplane"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("lies in the section plane"), std::string::npos) << r.output;
  j = nlohmann::json::parse(ReadBytes(dir.File("inplane/section.json")));
  EXPECT_EQ(j.at("layers").at(0).at("in_plane"), true);
  EXPECT_EQ(j.at("layers").at(0).at("lines"), 0);
  // A path with repeated vertices: merged, said so; its section crosses the floor's edge lines.
  r = RunCandi("section " + floor + " --path -1,5,-1,5,5,5,5,5,5,20 --thickness 0.2 -o " + dir.File("path"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("2 repeated vertices merged"), std::string::npos) << r.output;
  j = nlohmann::json::parse(ReadBytes(dir.File("path/section.json")));
  EXPECT_GT(j.at("layers").at(0).at("points"), 100);
  EXPECT_EQ(j.at("section").at("kind"), "path");
  EXPECT_NEAR(j.at("section").at("length").get<double>(), 21.0, 1e-9);
}

}  // namespace
}  // namespace candi::testing

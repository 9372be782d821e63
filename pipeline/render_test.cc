#include "pipeline/render.h"

#include <gtest/gtest.h>

#include "core/check.h"
#include "io/point_io.h"
#include "render/archive_pack.h"
#include "render/synthetic_scene.h"
#include "render/view_json.h"
#include "tests/util/option_check.h"
#include "tests/util/test_util.h"

namespace candi::pipeline {
namespace {

using testing::ExpectEachBreakRejected;
using testing::TempDir;

// Two overlapping sheets in survey coordinates (a shift of 10^6 m), written as double PLYs.
std::vector<PointCloud> Sheets() {
  std::vector<PointCloud> clouds = {render::UniformRectangle(20000, 8, 6, 0, {200, 40, 40}, 1),
                                    render::UniformRectangle(20000, 8, 6, 0.5, {40, 200, 40}, 2)};
  for (PointCloud& c : clouds) {
    for (Eigen::Vector3d& p : c.positions) p += Eigen::Vector3d(500000.25, 9100000.5, 12);
  }
  return clouds;
}

std::vector<std::string> WriteSheets(const TempDir& dir) {
  std::vector<std::string> files;
  io::PointWriteOptions o;
  o.precision = io::PositionPrecision::kFloat64;
  for (const PointCloud& c : Sheets()) {
    files.push_back(dir.File("sheet" + std::to_string(files.size()) + ".ply"));
    io::WritePointCloud(files.back(), c, o);
  }
  return files;
}

RenderOptions Small() {
  RenderOptions o;
  o.width = 96;
  o.height = 64;
  o.repeat_level = 8;
  o.mode = RenderMode::kMemory;
  return o;
}

TEST(RenderOptions, DefaultsPassAndRulesAreChecked) {
  ExpectEachBreakRejected<RenderOptions>({}, {
      [](RenderOptions& o) { o.repeat_level = 0; },
      [](RenderOptions& o) { o.alpha = {0.5}, o.opaque = true; },
      [](RenderOptions& o) { o.alpha = {1.5}; },
      [](RenderOptions& o) { o.alpha = {0.5}, o.mode = RenderMode::kStream; },
      [](RenderOptions& o) { o.brightness = 0; },
  });
}

// A build draws its layers from memory: the same image as from the files it wrote.
TEST(RenderClouds, EqualsRenderingTheirFiles) {
  TempDir dir;
  const std::vector<std::string> files = WriteSheets(dir);
  RenderOptions o = Small();
  o.alpha = {0.5, 0.8};
  const RenderedImage from_files = RenderPointFiles(o, files);
  const std::vector<PointCloud> clouds = Sheets();
  DensityCache cache;
  const RenderedImage in_memory = RenderClouds(o, {&clouds[0], &clouds[1]}, files, {"a", "b"}, &cache);
  EXPECT_TRUE(from_files.result.sums == in_memory.result.sums);
  EXPECT_EQ(from_files.result.copies, in_memory.result.copies);
  EXPECT_EQ(in_memory.mode, "memory");
  // The density is estimated once per key.
  const sampling::DensityResult* first = &cache.Get("a", sampling::OpacityOptions(), clouds[0]);
  EXPECT_EQ(first, &cache.Get("a", sampling::OpacityOptions(), clouds[0]));
}

TEST(RenderPointFiles, EmptyInputsAndBadFilesAreInputErrors) {
  TempDir dir;
  io::WritePointCloud(dir.File("empty.ply"), PointCloud());
  EXPECT_THROW(RenderPointFiles(Small(), {dir.File("empty.ply")}), InputError);
  EXPECT_THROW(RenderPointFiles(Small(), {dir.File("missing.ply")}), InputError);
}

// The MPI split: every rank's share of the ensembles adds up to the whole image.
TEST(RenderArchiveEnsembles, SharesAddUpToTheWhole) {
  TempDir dir;
  const std::vector<std::string> files = WriteSheets(dir);
  render::PackFiles(render::PackOptions(), files, "", dir.File("archive"));
  const render::Archive archive(dir.File("archive"));
  const RenderOptions o = Small();
  const RenderedImage whole = RenderArchiveEnsembles(o, archive, 0, 1);
  EXPECT_EQ(whole.mode, "archive");
  EXPECT_EQ(whole.result.ensembles, 8);
  render::Accumulator sum(o.width, o.height);
  for (int rank = 0; rank < 3; ++rank) {
    const RenderedImage part = RenderArchiveEnsembles(o, archive, rank, 3);
    EXPECT_EQ(part.mode, "archive, MPI");
    sum.Merge(part.result.sums);
  }
  EXPECT_TRUE(sum == whole.result.sums);
  RenderOptions alpha = o;
  alpha.alpha = {0.5};
  EXPECT_THROW(RenderArchiveEnsembles(alpha, archive, 0, 1), std::invalid_argument);
}

TEST(WriteRender, ThePngAndItsProvenanceAndTheViewToRepeatIt) {
  TempDir dir;
  const std::vector<std::string> files = WriteSheets(dir);
  RenderOptions o = Small();
  o.brightness = 1.25;
  const RenderedImage image = RenderPointFiles(o, files);
  RenderOutputs out;
  out.png = dir.File("r.png");
  out.png16 = dir.File("r16.png");
  out.save_view = dir.File("r.view.json");
  out.inputs = files;
  EXPECT_EQ(WriteRender(o, image, out), 1.25);
  const io::PngImage png = io::ReadPng(out.png);
  EXPECT_EQ(png.image8.width(), 96);
  EXPECT_EQ(png.text.at("candi:inputs"), files[0] + " " + files[1]);
  EXPECT_EQ(png.text.at("candi:mode"), "memory");
  EXPECT_EQ(png.text.at("candi:repeat_level"), "8");
  EXPECT_EQ(io::ReadPng(out.png16).bit_depth, 16);
  // The saved view renders the same image again.
  RenderOptions again = Small();
  again.brightness = 1.25;
  again.view = render::LoadView(out.save_view);
  EXPECT_TRUE(RenderPointFiles(again, files).result.sums == image.result.sums);
}

}  // namespace
}  // namespace candi::pipeline

#include "pipeline/render.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "core/atomic_file.h"
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

RenderOptions SmallRender() {
  RenderOptions o;
  o.image.width = 96;
  o.image.height = 64;
  o.image.spbr.repeat_level = 8;
  o.mode = RenderMode::kMemory;
  return o;
}

TEST(RenderOptions, DefaultsPassAndRulesAreChecked) {
  ExpectEachBreakRejected<RenderOptions>(
      {}, {
              [](RenderOptions& o) { o.image.spbr.repeat_level = 0; },
              [](RenderOptions& o) { o.alpha = {0.5}, o.image.spbr.opaque = true; },
              [](RenderOptions& o) { o.alpha = {1.5}; },
              [](RenderOptions& o) { o.alpha = {0.5}, o.mode = RenderMode::kStream; },
              [](RenderOptions& o) { o.preview = 3, o.mode = RenderMode::kStream; },
              [](RenderOptions& o) { o.image.spbr.point_size = 0.5; },
          });
}

// A build draws its layers from memory: the same image as from the files it wrote.
TEST(RenderClouds, EqualsRenderingTheirFiles) {
  TempDir dir;
  const std::vector<std::string> files = WriteSheets(dir);
  RenderOptions o = SmallRender();
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

// Stream mode draws binary PLY and LAS from their records in place: the same image as through
// the reader (a clip that keeps every point takes that path), on 1 and 2 threads. A file's
// multiplicities are honoured (all 0: nothing drawn), and ignored when opaque, as in memory mode.
TEST(RenderPointFiles, StreamModeReadsRecordsInPlaceAndHonoursMultiplicities) {
  TempDir dir;
  std::vector<std::string> files = WriteSheets(dir);  // double PLYs
  io::PointWriteOptions las;
  files.push_back(dir.File("sheet.las"));
  io::WritePointCloud(files.back(), Sheets()[0], las);
  RenderOptions o = SmallRender();
  o.mode = RenderMode::kStream;
  const RenderedImage in_place = RenderPointFiles(o, files);
  EXPECT_EQ(in_place.mode, "stream");
  EXPECT_EQ(in_place.result.copies, 60000u);
  RenderOptions through_reader = o;
  through_reader.clip.planes.push_back({Eigen::Vector3d(0, 0, -1e9), Eigen::Vector3d::UnitZ()});  // keeps all
  through_reader.threads = 1;
  const RenderedImage read = RenderPointFiles(through_reader, files);
  EXPECT_EQ(read.result.copies, 60000u);
  EXPECT_TRUE(in_place.result.sums == read.result.sums) << "in place and through the reader differ";
  o.threads = 2;
  EXPECT_TRUE(RenderPointFiles(o, files).result.sums == in_place.result.sums);

  // A LAS header's bounds are not trusted where the records are read: wrong ones (a box 10 km
  // away) frame the same first view as memory mode's, which frames the points.
  {
    std::string bytes = ReadFileToString(files.back());
    const double far_away[6] = {510000, 500000, 9110000, 9100000, 1000, 900};  // max x, min x, max y, ...
    std::memcpy(&bytes[179], far_away, sizeof(far_away));
    const std::string liar = dir.File("liar.las");
    WriteFileAtomic(liar, bytes);
    RenderOptions memory = SmallRender();
    const RenderedImage m = RenderPointFiles(memory, {liar});
    const RenderedImage s = RenderPointFiles(o, {liar});
    EXPECT_EQ(s.mode, "stream");
    EXPECT_TRUE(s.world_camera.eye.isApprox(m.world_camera.eye, 1e-9)) << s.world_camera.eye.transpose();
    EXPECT_TRUE(s.world_camera.target.isApprox(m.world_camera.target, 1e-9));
  }

  PointCloud none = Sheets()[0];
  none.AddScalarField(render::kMultiplicityField);  // every point's multiplicity 0
  const std::string zero = dir.File("zero.ply");
  io::WritePointCloud(zero, none);
  EXPECT_EQ(RenderPointFiles(o, {zero}).result.copies, 0u);
  o.image.spbr.opaque = true;
  EXPECT_EQ(RenderPointFiles(o, {zero}).result.copies, 20000u);
}

TEST(RenderPointFiles, EmptyInputsAndBadFilesAreInputErrors) {
  TempDir dir;
  io::WritePointCloud(dir.File("empty.ply"), PointCloud());
  EXPECT_THROW(RenderPointFiles(SmallRender(), {dir.File("empty.ply")}), InputError);
  EXPECT_THROW(RenderPointFiles(SmallRender(), {dir.File("missing.ply")}), InputError);
}

// The MPI split: every rank's share of the ensembles adds up to the whole image.
TEST(RenderArchiveEnsembles, SharesAddUpToTheWhole) {
  TempDir dir;
  const std::vector<std::string> files = WriteSheets(dir);
  render::PackFiles(render::PackOptions(), files, "", dir.File("archive"));
  const render::Archive archive(dir.File("archive"));
  const RenderOptions o = SmallRender();
  const RenderedImage whole = RenderArchiveEnsembles(o, archive, 0, 1);
  EXPECT_EQ(whole.mode, "archive");
  EXPECT_EQ(whole.result.ensembles, 8);
  render::Accumulator sum(o.image.width, o.image.height);
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
  RenderOptions o = SmallRender();
  o.image.brightness = Brightness::Gain(1.25);
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
  RenderOptions again = SmallRender();
  again.image.brightness = Brightness::Gain(1.25);
  again.view = render::LoadView(out.save_view);
  EXPECT_TRUE(RenderPointFiles(again, files).result.sums == image.result.sums);
}

TEST(RenderPointFiles, ColouredByAFieldWithItsLegendInThePng) {
  // A sheet at survey coordinates whose field runs from -1 (west) to +1 (east), one point NaN.
  TempDir dir;
  PointCloud sheet = Sheets()[0];
  const int k = sheet.AddScalarField("distance");
  const Box3d box = sheet.LocalBounds();
  for (size_t i = 0; i < sheet.size(); ++i) {
    sheet.scalars[k].Set(i, 2 * (sheet.positions[i].x() - box.min.x()) / (box.max.x() - box.min.x()) - 1);
  }
  sheet.scalars[k].Set(0, std::numeric_limits<double>::quiet_NaN());
  const std::string file = dir.File("sheet.ply");
  io::WritePointCloud(file, sheet);
  RenderOptions o = SmallRender();
  o.image.width = 640;
  o.image.height = 480;
  o.image.spbr.opaque = true;
  o.view = render::Camera();
  const Eigen::Vector3d centre = sheet.frame.origin + box.Center();  // the 8 x 6 m sheet fills most of the view
  o.view->eye = centre + Eigen::Vector3d(0, 0, 12);
  o.view->target = centre;
  o.view->up = Eigen::Vector3d::UnitY();
  o.view->width = 640;
  o.view->height = 480;
  o.colour_by.field = "distance";
  o.colour_by.lo = -1;
  o.colour_by.hi = 1;
  const RenderedImage image = RenderPointFiles(o, {file});
  ASSERT_TRUE(image.legend.has_value());
  EXPECT_EQ(image.legend->scale, FieldScale::kDiverging);
  EXPECT_EQ(image.legend->undefined, 1u);
  RenderOutputs out;
  out.png = dir.File("coloured.png");
  WriteRender(o, image, out);
  const io::PngImage png = io::ReadPng(out.png);
  EXPECT_EQ(png.text.at("candi:colour_by").rfind("distance diverging -1 1", 0), 0u) << png.text.at("candi:colour_by");
  // The west of the sheet blue, the east red (above the legend, which sits bottom left).
  const Image8& im = png.image8;
  auto mean = [&](int x0, int x1, int c) {
    double sum = 0;
    int n = 0;
    for (int y = 100; y < 220; ++y) {
      for (int x = x0; x < x1; ++x, ++n) sum += im.at(x, y, c);
    }
    return sum / n;
  };
  EXPECT_GT(mean(110, 210, 2), 1.5 * mean(110, 210, 0));  // blue
  EXPECT_GT(mean(430, 530, 0), 1.5 * mean(430, 530, 2));  // red
  // The legend: the scale's deep blue and red at the bottom left, where the sheet is not.
  int legend_blue = 0;
  for (int y = 430; y < 470; ++y) {  // below the sheet
    for (int x = 0; x < 200; ++x) legend_blue += im.at(x, y, 2) > im.at(x, y, 0) + 80;
  }
  EXPECT_GT(legend_blue, 50);
  // A field the file lacks, stream mode and an archive are refused, naming why.
  o.colour_by.field = "lod95";
  try {
    RenderPointFiles(o, {file});
    FAIL() << "no error for a missing field";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("lod95"), std::string::npos) << e.what();
  }
  o.colour_by.field = "distance";
  o.mode = RenderMode::kStream;
  EXPECT_THROW(RenderPointFiles(o, {file}), std::invalid_argument);

  // Packed coloured (candi pack --colour-by), the archive renders with the same legend.
  render::PackFiles(render::PackOptions(), {file}, "", dir.File("arch"), nullptr, o.colour_by);
  const render::Archive archive(dir.File("arch"));
  RenderOptions a = o;
  a.mode = RenderMode::kAuto;
  a.colour_by = FieldColouring();
  const RenderedImage packed = RenderArchiveEnsembles(a, archive, 0, 1);
  ASSERT_TRUE(packed.legend.has_value());
  EXPECT_EQ(packed.legend->field, "distance");
  EXPECT_EQ(packed.legend->undefined, 1u);
  out.png = dir.File("archive.png");
  WriteRender(a, packed, out);
  EXPECT_EQ(io::ReadPng(out.png).text.at("candi:colour_by"), png.text.at("candi:colour_by"));
  a.colour_by = o.colour_by;  // an archive holds colours, not fields: colouring it again is refused
  EXPECT_THROW(RenderArchiveEnsembles(a, archive, 0, 1), std::invalid_argument);
}

}  // namespace
}  // namespace candi::pipeline

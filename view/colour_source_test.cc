// An archive packed coloured by a field (candi pack --colour-by) keeps its colouring wherever it
// is opened: candi view's source carries the legend, and candi publish's site.json carries it with
// the runs a page decodes a picked colour from, which give the value the server gives.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <string>
#include <nlohmann/json.hpp>

#include "core/atomic_file.h"
#include "io/point_io.h"
#include "render/archive_pack.h"
#include "render/synthetic_scene.h"
#include "tests/util/test_util.h"
#include "view/publish.h"
#include "view/source.h"

namespace candi::view {
namespace {

using candi::testing::TempDir;

TEST(ViewerSource, AnArchivePackedColouredKeepsItsLegendInViewAndSite) {
  TempDir dir;
  PointCloud sheet = render::UniformRectangle(3000, 8, 6, 0, {10, 200, 10}, 5);
  sheet.frame.origin = Eigen::Vector3d(416000, 9168000, 100);
  const int k = sheet.AddScalarField("distance");
  for (size_t i = 0; i < sheet.size(); ++i) sheet.scalars[k].Set(i, 0.01 * (sheet.positions[i].x() / 4 - 1));
  io::WritePointCloud(dir.File("deviation.ply"), sheet);
  FieldColouring colour_by;
  colour_by.field = "distance";
  render::PackFiles(render::PackOptions(), {dir.File("deviation.ply")}, "", dir.File("arch"), nullptr, colour_by);

  // candi view ARCHIVE: the legend, from the manifest (auto range: +-the 98th percentile of |v|).
  const ViewerSource source = OpenViewerSource(dir.File("arch"), render::Orientation());
  ASSERT_TRUE(source.legend.has_value());
  EXPECT_EQ(source.legend->scale, FieldScale::kDiverging);
  EXPECT_NEAR(source.legend->hi, 0.0098, 2e-4);
  EXPECT_EQ(source.legend->lo, -source.legend->hi);

  // candi publish: site.json's scene has the legend and its runs.
  PublishOptions o;
  o.repeat_level = 4;
  PublishSite(o, dir.File("arch"), dir.File("site"), render::Orientation());
  const nlohmann::json site = nlohmann::json::parse(ReadFileToString(dir.File("site/site.json")));
  const nlohmann::json& legend = site.at("scene").at("legend");
  EXPECT_EQ(legend.at("field"), "distance");
  EXPECT_EQ(legend.at("lo").get<double>(), source.legend->lo);
  const int steps = legend.at("steps").get<int>();
  ASSERT_EQ(steps, FieldLegend::kColourSteps);
  // The page's decoding (site.js, valueOfColour), here in C++: each colour's first and last
  // sample; every archived colour then reads back as the server reads it.
  std::map<uint32_t, std::pair<int, int>> runs;
  for (const nlohmann::json& r : legend.at("runs")) {
    const uint32_t c = r[0].get<uint32_t>();
    auto it = runs.find(c);
    if (it == runs.end()) runs[c] = {r[1].get<int>(), r[2].get<int>()};
    else it->second.second = r[2].get<int>();
  }
  const render::Archive archive(dir.File("arch"));
  const PointCloud packed = archive.ReadAll();
  const double step = (source.legend->hi - source.legend->lo) / steps;
  size_t decoded = 0;
  for (size_t i = 0; i < packed.size(); ++i) {
    const Rgb8 c = packed.colors[i];
    double half = 0;
    const std::optional<double> server = source.legend->ValueOfColour(c, &half);
    if (!server) {
      EXPECT_TRUE(c == kOutOfRangeGrey) << i;
      continue;
    }
    const auto it = runs.find((c.r << 16) | (c.g << 8) | c.b);
    if (it == runs.end()) {  // a colour between two samples: the page reads it between them too
      EXPECT_NEAR(half, 0.5 * step, 1e-15) << i;
      continue;
    }
    const double page = source.legend->lo + 0.5 * (it->second.first + it->second.second) * step;
    EXPECT_NEAR(page, *server, 1e-12 * (1 + std::abs(*server))) << i;
    const double value = 0.01 * ((packed.WorldPosition(i).x() - 416000) / 4 - 1);
    EXPECT_NEAR(page, value, half + 1e-6) << i;
    ++decoded;
  }
  EXPECT_GT(decoded, 2900u);  // all but the 2 % beyond the auto range
}

}  // namespace
}  // namespace candi::view

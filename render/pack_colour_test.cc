// Packing point files coloured by a scalar field (candi pack --colour-by): every point gets its
// value's colour, with one colouring over all the files; the manifest records the colouring and
// reads back equal; a malformed record is refused naming its field.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>

#include "core/atomic_file.h"
#include "core/check.h"
#include "io/point_io.h"
#include "render/archive.h"
#include "render/archive_pack.h"
#include "render/synthetic_scene.h"
#include "tests/util/test_util.h"

namespace candi::render {
namespace {

using candi::testing::TempDir;

// A sheet at survey coordinates whose distance is x / 4 - 1 (-1 west, +1 east at x = 8 m), and
// one point without a value.
PointCloud Sheet(uint64_t seed, double shift_x) {
  PointCloud sheet = UniformRectangle(4000, 8, 6, 0, {10, 200, 10}, seed);
  sheet.frame.origin = Eigen::Vector3d(416000 + shift_x, 9168000, 100);
  const int k = sheet.AddScalarField("distance");
  for (size_t i = 0; i < sheet.size(); ++i) sheet.scalars[k].Set(i, (sheet.positions[i].x() + shift_x) / 4 - 1);
  sheet.scalars[k].Set(0, std::numeric_limits<double>::quiet_NaN());
  return sheet;
}

TEST(PackColour, PointsTakeTheirFieldsColourAndTheManifestRecordsTheColouring) {
  TempDir dir;
  // Two files, the second shifted 8 m east: its values run from +1 to +3, beyond the range the
  // first alone would give, so one colouring over both must be resolved first.
  io::WritePointCloud(dir.File("west.ply"), Sheet(1, 0));
  io::WritePointCloud(dir.File("east.ply"), Sheet(2, 8));
  FieldColouring colour_by;
  colour_by.field = "distance";
  colour_by.lo = -1;
  colour_by.hi = 1;
  PackOptions o;
  o.chunk_points = 512;
  const PackSummary s = PackFiles(o, {dir.File("west.ply"), dir.File("east.ply")}, "", dir.File("arch"), nullptr,
                                  colour_by);
  ASSERT_TRUE(s.colour_by.has_value());
  const Archive archive(dir.File("arch"));
  const ArchiveManifest& m = archive.manifest();
  ASSERT_TRUE(m.colour_by.has_value());
  const FieldLegend& l = *m.colour_by;
  EXPECT_EQ(l.field, "distance");
  EXPECT_EQ(l.scale, FieldScale::kDiverging);  // auto: a field named distance
  EXPECT_EQ(l.lo, -1.0);
  EXPECT_EQ(l.hi, 1.0);
  EXPECT_EQ(l.count, 8000u);
  EXPECT_EQ(l.undefined, 2u);
  // The east file's values beyond +1 (all but those at x = 0 exactly, and its NaN) are grey.
  EXPECT_GE(l.outside, 3990u);
  EXPECT_LE(l.outside, 3999u);
  // Every archived point's colour reads back as its value (x / 4 - 1 of its world x) within the
  // colour's width, or is grey where the value is outside or missing.
  const PointCloud packed = archive.ReadAll();
  ASSERT_EQ(packed.size(), 8000u);
  size_t grey = 0, checked = 0;
  for (size_t i = 0; i < packed.size(); ++i) {
    const double value = (packed.WorldPosition(i).x() - 416000) / 4 - 1;
    double half = 0;
    const std::optional<double> back = l.ValueOfColour(packed.colors[i], &half);
    if (!back) {
      ++grey;
      continue;
    }
    // The archive quantizes positions (< 0.1 mm here): the value moves by a forty-thousandth of it.
    EXPECT_NEAR(*back, value, half + 1e-4) << i;
    ++checked;
  }
  EXPECT_EQ(grey, l.outside + l.undefined);
  EXPECT_GT(checked, 3900u);
  // The same colouring and archive on one thread (the colours are a function of the values).
  o.threads = 1;
  PackFiles(o, {dir.File("west.ply"), dir.File("east.ply")}, "", dir.File("arch1"), nullptr, colour_by);
  EXPECT_EQ(ReadFileToString(dir.File("arch1/data-00000.bin")), ReadFileToString(dir.File("arch/data-00000.bin")));
  // A file without the field is named, and nothing is written.
  colour_by.field = "lod95";
  try {
    PackFiles(o, {dir.File("west.ply")}, "", dir.File("arch2"), nullptr, colour_by);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("west.ply"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("lod95"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir.File("arch2")));
}

TEST(PackColour, ManifestRoundTripAndMalformedColouringNamed) {
  ArchiveManifest m;
  m.bounds.min = Eigen::Vector3d::Zero();
  m.bounds.max = Eigen::Vector3d::Ones();
  m.layers.push_back({"a", 0});
  FieldLegend classes;
  classes.field = "classification";
  classes.scale = FieldScale::kClasses;
  classes.lo = 2;
  classes.hi = 6;
  classes.classes = {2, 6};
  classes.count = 10;
  classes.undefined = 1;
  m.colour_by = classes;
  const ArchiveManifest back = ArchiveManifest::FromJson(m.ToJson(), "manifest.json");
  ASSERT_TRUE(back.colour_by.has_value());
  EXPECT_EQ(back.colour_by->field, "classification");
  EXPECT_EQ(back.colour_by->scale, FieldScale::kClasses);
  EXPECT_EQ(back.colour_by->classes, classes.classes);
  EXPECT_EQ(back.colour_by->count, 10u);
  EXPECT_EQ(back.colour_by->undefined, 1u);
  m.colour_by.reset();
  EXPECT_FALSE(ArchiveManifest::FromJson(m.ToJson(), "manifest.json").colour_by.has_value());

  // Edited by hand: each bad value is refused naming its field.
  FieldLegend l;
  l.field = "distance";
  l.scale = FieldScale::kDiverging;
  l.lo = -1;
  l.hi = 1;
  m.colour_by = l;
  const std::string good = m.ToJson();
  struct Case {
    std::string from, to, field;
  };
  for (const Case& c : {Case{"\"diverging\"", "\"auto\"", "colour_by.scale"},
                        Case{"\"diverging\"", "\"rainbow\"", "colour_by.scale"},
                        Case{"\"lo\": -1.0", "\"lo\": 1.0", "colour_by"},
                        Case{"\"field\": \"distance\"", "\"field\": 3", "colour_by.field"},
                        Case{"\"count\": 0", "\"count\": -4", "colour_by.count"}}) {
    std::string text = good;
    const size_t at = text.find(c.from);
    ASSERT_NE(at, std::string::npos) << c.from << " in " << good;
    text.replace(at, c.from.size(), c.to);
    try {
      ArchiveManifest::FromJson(text, "manifest.json");
      FAIL() << c.to << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.field), std::string::npos) << c.to << ": " << e.what();
    }
  }
}

}  // namespace
}  // namespace candi::render

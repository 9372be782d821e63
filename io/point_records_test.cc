#include "io/point_records.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>

#include "core/check.h"
#include "core/rng.h"
#include "io/point_io.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using candi::testing::TempDir;

// Points in survey coordinates with colours.
PointCloud Survey(size_t n) {
  PointCloud c;
  c.schema.colors = true;
  c.schema.position_type = ScalarType::kFloat64;
  c.SetSchema(c.schema);
  c.frame.origin = Eigen::Vector3d(416000, 9168000, 200);
  c.Resize(n);
  Rng rng(7);
  for (size_t i = 0; i < n; ++i) {
    c.positions[i] = Eigen::Vector3d(rng.Uniform(-50, 50), rng.Uniform(-20, 20), rng.Uniform(-3, 3));
    c.colors[i] = {static_cast<uint8_t>(i), static_cast<uint8_t>(3 * i), static_cast<uint8_t>(7 * i)};
  }
  return c;
}

// Float and double PLY and LAS: the records give Read()'s positions and colours, and their
// bounds are the reader's, on any thread count.
TEST(PointRecords, GiveTheReadersPointsAndBounds) {
  TempDir dir;
  const PointCloud cloud = Survey(200000);
  using C = PointRecordLayout::Coordinates;
  struct Case {
    std::string name;
    PositionPrecision precision;
    C coordinates;
  };
  for (const Case& f : {Case{"f.ply", PositionPrecision::kFloat32, C::kFloat32},
                        Case{"d.ply", PositionPrecision::kFloat64, C::kFloat64},
                        Case{"p.las", PositionPrecision::kAuto, C::kLasInt32}}) {
    const std::string path = dir.File(f.name);
    PointWriteOptions w;
    w.precision = f.precision;
    WritePointCloud(path, cloud, w);
    const PointCloud read = ReadPointCloud(path);
    auto reader = OpenPointReader(path);
    const std::optional<PointRecordLayout> layout = reader->record_layout();
    ASSERT_TRUE(layout) << f.name;
    EXPECT_EQ(layout->coordinates, f.coordinates) << f.name;
    const MappedFile map(path);
    ASSERT_TRUE(HoldsRecords(map, *layout));
    size_t mismatches = 0;
    ForEachRecord(*layout, map.data() + layout->first_byte, static_cast<size_t>(layout->count), 0,
                  [&](size_t i, const Eigen::Vector3d& p, uint32_t rgb) {
                    const Rgb8 c = read.colors[i];
                    mismatches += p != read.positions[i] || rgb != (uint32_t{c.r} << 16 | uint32_t{c.g} << 8 | c.b);
                  });
    EXPECT_EQ(mismatches, 0u) << f.name;
    const std::optional<Box3d> box = RecordBounds(map, *layout);
    ASSERT_TRUE(box) << f.name;
    const Box3d world = box->Translated(reader->info().frame.origin), expected = read.WorldBounds();
    EXPECT_EQ(world.min, expected.min) << f.name;
    EXPECT_EQ(world.max, expected.max) << f.name;
  }
}

// A double PLY's coordinates in any order are records; mixed types and lists are not.
TEST(PointRecords, PlyLayoutsOfDoublesInAnyOrderButNotMixedTypes) {
  TempDir dir;
  auto layout_of = [&](const std::string& properties, size_t record_bytes) {
    const std::string path = dir.File("h.ply");
    std::ofstream out(path, std::ios::binary);
    out << "ply\nformat binary_little_endian 1.0\nelement vertex 1\n" << properties << "end_header\n";
    out << std::string(record_bytes, '\0');
    out.close();
    return OpenPointReader(path)->record_layout();
  };
  const auto zyx = layout_of("property double z\nproperty double y\nproperty double x\n", 24);
  ASSERT_TRUE(zyx);
  EXPECT_EQ(zyx->coordinates, PointRecordLayout::Coordinates::kFloat64);
  EXPECT_EQ(zyx->xyz[0], 16u);
  EXPECT_EQ(zyx->xyz[2], 0u);
  EXPECT_FALSE(layout_of("property double x\nproperty float y\nproperty double z\n", 20));
  EXPECT_FALSE(layout_of("property float x\nproperty float y\nproperty double z\n", 16));
  EXPECT_FALSE(layout_of("property int x\nproperty int y\nproperty int z\n", 12));
  // A property named twice is refused by the header (so no record offset is ever left unset).
  EXPECT_THROW(layout_of("property float x\nproperty float x\nproperty float y\nproperty float z\n", 16),
               InputError);
  EXPECT_THROW(layout_of("property float x\nproperty float y\nproperty float z\nproperty uchar red\n"
                         "property uchar red\nproperty uchar green\n", 15),
               InputError);
  const auto rgb = layout_of("property float x\nproperty float y\nproperty float z\nproperty uchar blue\n"
                             "property uchar green\nproperty uchar red\n", 15);
  ASSERT_TRUE(rgb);
  EXPECT_EQ(rgb->rgb[0], 14);
  EXPECT_EQ(rgb->rgb[2], 12);
}

// NaN or infinity anywhere, or a file cut short: no bounds (the reader then says where).
TEST(PointRecords, NonFiniteOrMissingRecordsGiveNoBounds) {
  TempDir dir;
  PointCloud cloud = Survey(100000);
  const std::string path = dir.File("d.ply");
  PointWriteOptions w;
  w.precision = PositionPrecision::kFloat64;
  WritePointCloud(path, cloud, w);
  std::optional<PointRecordLayout> layout = OpenPointReader(path)->record_layout();
  ASSERT_TRUE(layout);
  {
    const MappedFile map(path);
    EXPECT_TRUE(RecordBounds(map, *layout));
  }
  // The 77777th record's y is NaN.
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::string bad = bytes;
  std::memcpy(&bad[layout->first_byte + 77777 * layout->stride + layout->xyz[1]], &nan, 8);
  std::ofstream(dir.File("nan.ply"), std::ios::binary) << bad;
  {
    const MappedFile map(dir.File("nan.ply"));
    EXPECT_FALSE(RecordBounds(map, *layout));
  }
  std::ofstream(dir.File("cut.ply"), std::ios::binary) << bytes.substr(0, bytes.size() - 5);
  const MappedFile cut(dir.File("cut.ply"));
  EXPECT_FALSE(HoldsRecords(cut, *layout));
  EXPECT_FALSE(RecordBounds(cut, *layout));
}

}  // namespace
}  // namespace candi::io

#include "io/point_io.h"
#include "io/e57/e57_writer.h"
#include "io/shift_sidecar.h"

#include <gtest/gtest.h>

#include "core/check.h"
#include "tests/util/input_error.h"
#include "tests/util/option_check.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using testing::TempDir;
using testing::WriteBytes;

std::string ErrorOf(const std::string& path) {
  return testing::InputErrorMessage([&] { DetectPointFormat(path); });
}

TEST(DetectPointFormat, ExtensionConfirmedByContent) {
  TempDir dir;
  WriteBytes(dir.File("a.ply"), "ply\nformat ascii 1.0\n");
  WriteBytes(dir.File("b.xyz"), "1 2 3\n");
  WriteBytes(dir.File("c.PTS"), "1\n1 2 3 4\n");
  EXPECT_EQ(DetectPointFormat(dir.File("a.ply")), PointFormat::kPly);
  EXPECT_EQ(DetectPointFormat(dir.File("b.xyz")), PointFormat::kXyz);
  EXPECT_EQ(DetectPointFormat(dir.File("c.PTS")), PointFormat::kPts);
}

TEST(DetectPointFormat, MismatchIsAnErrorNotAGuess) {
  TempDir dir;
  WriteBytes(dir.File("las.ply"), std::string("LASF") + std::string(300, '\0'));
  EXPECT_NE(ErrorOf(dir.File("las.ply")).find("extension says PLY but the content is LAS"), std::string::npos);
  WriteBytes(dir.File("bin.xyz"), std::string("\x01\x02\x00\x05", 4));
  EXPECT_NE(ErrorOf(dir.File("bin.xyz")).find("content is binary data"), std::string::npos);
  WriteBytes(dir.File("x.foo"), "1 2 3\n");
  EXPECT_NE(ErrorOf(dir.File("x.foo")).find("unknown point-file extension '.foo'"), std::string::npos);
}

TEST(DetectPointFormat, EmptyAndDxfAreRefusedClearlyLazIsLas) {
  TempDir dir;
  WriteBytes(dir.File("e.ply"), "");
  EXPECT_NE(ErrorOf(dir.File("e.ply")).find("byte 0: empty file"), std::string::npos);
  std::string laz = "LASF" + std::string(300, '\0');
  laz[104] = static_cast<char>(0x83);  // LASzip: point format 3 with the compression bits
  WriteBytes(dir.File("z.las"), laz);
  WriteBytes(dir.File("z.laz"), laz);
  EXPECT_EQ(DetectPointFormat(dir.File("z.las")), PointFormat::kLas);  // the LAS reader decodes it
  EXPECT_EQ(DetectPointFormat(dir.File("z.laz")), PointFormat::kLas);
  WriteBytes(dir.File("p.laz"), "ply\nformat ascii 1.0\n");
  EXPECT_NE(ErrorOf(dir.File("p.laz")).find("content is PLY"), std::string::npos);
  EXPECT_EQ(OutputPointFormat(dir.File("out.laz")), PointFormat::kLas);  // LAZ-compressed
  WriteBytes(dir.File("d.dxf"), "  0\nSECTION\n  2\nHEADER\n");
  EXPECT_NE(ErrorOf(dir.File("d.dxf")).find("not a point file"), std::string::npos);
  WriteBytes(dir.File("d.ply"), "AutoCAD Binary DXF\r\n\x1a");
  EXPECT_NE(ErrorOf(dir.File("d.ply")).find("binary DXF"), std::string::npos);
  EXPECT_NE(ErrorOf(dir.File("missing.ply")).find("cannot open"), std::string::npos);
}

TEST(DetectPointFormat, RealBinaryDxfIsRefusedRealLazIsLas) {
  EXPECT_EQ(DetectPointFormat(testing::SourceDir() + "/tests/data/laz/simple.laz"),
            PointFormat::kLas);
  CANDI_REQUIRE_SHARED_DATA(dxf, "dxf/bin_dxf_r2000.dxf");
  EXPECT_NE(ErrorOf(dxf).find("binary DXF"), std::string::npos) << ErrorOf(dxf);
  CANDI_REQUIRE_SHARED_DATA(laz, "las/autzen_trim.laz");
  EXPECT_EQ(DetectPointFormat(laz), PointFormat::kLas);
}

TEST(ShiftSidecar, RoundTripAndStaleSidecarIgnored) {
  TempDir dir;
  WriteBytes(dir.File("p.xyz"), "1 2 3\n");
  LocalFrame f;
  f.origin = Eigen::Vector3d(500000, 4500000, 100);
  WriteShiftSidecar(dir.File("p.xyz"), f);
  ASSERT_TRUE(ReadShiftSidecar(dir.File("p.xyz")).has_value());
  EXPECT_EQ(*ReadShiftSidecar(dir.File("p.xyz")), f);
  WriteBytes(dir.File("p.xyz"), "1 2 3\n4 5 6\n");  // rewritten by another tool
  EXPECT_FALSE(ReadShiftSidecar(dir.File("p.xyz")).has_value());
  WriteBytes(dir.File("p.xyz.shift.json"), "{ nonsense }");
  EXPECT_THROW(ReadShiftSidecar(dir.File("p.xyz")), InputError);
}

TEST(IoModuleOptions, DefaultsPassCheck) {
  EXPECT_NO_THROW(PointReadOptions().Check());
  EXPECT_NO_THROW(PointWriteOptions().Check());
  EXPECT_NO_THROW(E57WriteOptions().Check());
}

TEST(PointWriteOptions, LasScaleMustBeFiniteAndPositive) {
  PointWriteOptions o;
  o.las_scale = Eigen::Vector3d(0.001, 0, 0.001);
  EXPECT_EQ(testing::OptionCheckMessage(o),
            "PointWriteOptions::las_scale = (0.001, 0, 0.001); must be finite and > 0");
}

TEST(PointWriteOptions, DefaultsPassAndBadValuesNameTheField) {
  EXPECT_NO_THROW(PointWriteOptions{}.Check());
  PointWriteOptions o;
  o.las_point_format = 5;
  try {
    o.Check();
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("las_point_format = 5"), std::string::npos);
  }
}

}  // namespace
}  // namespace candi::io

namespace candi::io {
namespace {

TEST(PointReadOptions, WithoutScalarFieldsEveryFormatKeepsGeometryAndColourOnly) {
  testing::TempDir dir;
  PointCloud cloud;
  cloud.schema.colors = true;
  cloud.schema.scalars = {{"intensity", ScalarType::kFloat32}, {"Deviation", ScalarType::kFloat64}};
  cloud.SetSchema(cloud.schema);
  cloud.Resize(3);
  for (size_t i = 0; i < 3; ++i) {
    cloud.positions[i] = Eigen::Vector3d(i, 2.0 * i, 500000.25);
    cloud.colors[i] = {static_cast<uint8_t>(i), 9, 99};
  }
  PointReadOptions geometry_only;
  geometry_only.scalar_fields = false;
  for (const char* name : {"a.ply", "a.las", "a.xyz"}) {
    WritePointCloud(dir.File(name), cloud);
    const PointCloud all = ReadPointCloud(dir.File(name));
    const PointCloud lean = ReadPointCloud(dir.File(name), geometry_only);
    EXPECT_FALSE(all.schema.scalars.empty()) << name;
    EXPECT_TRUE(lean.schema.scalars.empty()) << name;
    ASSERT_EQ(lean.size(), 3u) << name;
    EXPECT_EQ(lean.colors, cloud.colors) << name;
    for (size_t i = 0; i < 3; ++i) EXPECT_EQ(lean.WorldPosition(i), all.WorldPosition(i)) << name;
  }
}

}  // namespace
}  // namespace candi::io

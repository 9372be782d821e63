#include "io/las/las_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>

#include "core/check.h"
#include "io/las/las_header.h"
#include "io/point_io.h"
#include "tests/util/input_error.h"
#include "tests/util/las_bytes.h"
#include "tests/util/read_in_chunks.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using ::candi::testing::FileExists;
using ::candi::testing::GetLE;
using ::candi::testing::InputErrorMessage;
using ::candi::testing::LasPointRecords;
using ::candi::testing::PutLE;
using ::candi::testing::ReadBytes;
using ::candi::testing::ReadInChunks;
using ::candi::testing::TempDir;
using ::candi::testing::WriteBytes;

// ---- helpers ----

PointCloud ReadAll(const std::string& path, size_t chunk_size) {
  return ReadInChunks(*OpenLasReader(path), chunk_size);
}

// Points around a survey origin with mm detail, every kind of attribute.
PointCloud MakeSurveyCloud(size_t n) {
  PointCloud cloud;
  PointSchema schema;
  schema.colors = true;
  schema.normals = true;
  schema.scalars = {{las_field::kIntensity, ScalarType::kFloat32},
                    {las_field::kClassification, ScalarType::kFloat32},
                    {las_field::kGpsTime, ScalarType::kFloat64},
                    {"confidence", ScalarType::kFloat32},
                    {"range_m", ScalarType::kFloat64}};
  cloud.SetSchema(schema);
  cloud.frame.origin = Eigen::Vector3d(500000.0, 4500000.0, 0.0);
  cloud.Resize(n);
  for (size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i);
    const Eigen::Vector3d world(500000.123 + 0.0137 * t, 4500000.456 - 0.0071 * t,
                                100.789 + 0.0003 * t);
    cloud.positions[i] = cloud.frame.ToLocal(world);
    cloud.colors[i] = Rgb8{static_cast<uint8_t>(i % 256), static_cast<uint8_t>((3 * i) % 256),
                           static_cast<uint8_t>(255 - i % 256)};
    cloud.normals[i] = Eigen::Vector3f(std::cos(0.1f * i), std::sin(0.1f * i), 0.5f).normalized();
    cloud.scalars[0].f32[i] = static_cast<float>((i * 37) % 65536);
    cloud.scalars[1].f32[i] = static_cast<float>(i % 32);
    cloud.scalars[2].f64[i] = 245379.39843682514 + 1.0e-5 * t;
    cloud.scalars[3].f32[i] = 0.25f * static_cast<float>(i) - 3.1f;
    cloud.scalars[4].f64[i] = 1234.56789012345 + t / 3.0;
  }
  return cloud;
}

PointCloud MakePlainCloud(size_t n, const std::vector<ScalarFieldSpec>& scalars = {}) {
  PointCloud cloud;
  PointSchema schema;
  schema.scalars = scalars;
  cloud.SetSchema(schema);
  cloud.Resize(n);
  for (size_t i = 0; i < n; ++i) cloud.positions[i] = Eigen::Vector3d(i, 2.0 * i, 0.5 * i);
  return cloud;
}

void ExpectBoundsMatchHeader(const std::string& path) {
  auto reader = OpenLasReader(path);
  const PointCloud cloud = ReadAll(path, 1 << 16);
  ASSERT_TRUE(reader->info().header_bounds.has_value());
  const Box3d header = *reader->info().header_bounds;
  const Box3d computed = cloud.WorldBounds();
  const Eigen::Vector3d scale = reader->info().meta.las.scale;
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(computed.min[k], header.min[k], scale[k]) << path << " axis " << k;
    EXPECT_NEAR(computed.max[k], header.max[k], scale[k]) << path << " axis " << k;
  }
}

void ExpectSameVlrs(const std::vector<LasVlr>& a, const std::vector<LasVlr>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].user_id, b[i].user_id);
    EXPECT_EQ(a[i].record_id, b[i].record_id);
    EXPECT_EQ(a[i].description, b[i].description);
    EXPECT_EQ(a[i].data, b[i].data);
    EXPECT_EQ(a[i].extended, b[i].extended);
  }
}

void ExpectSamePoints(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.schema, b.schema);
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.WorldPosition(i), b.WorldPosition(i)) << "point " << i;
    if (a.schema.colors) {
      ASSERT_EQ(a.colors[i], b.colors[i]) << "point " << i;
    }
  }
  for (size_t f = 0; f < a.scalars.size(); ++f) {
    for (size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(a.scalars[f].Get(i), b.scalars[f].Get(i)) << a.scalars[f].spec.name << " " << i;
    }
  }
}

// A small valid LAS 1.2 format 3 file (10 points) for the bad-input tests.
std::string ValidSmallLas(const TempDir& dir) {
  PointCloud cloud = MakePlainCloud(10, {{las_field::kGpsTime, ScalarType::kFloat64}});
  cloud.schema.colors = true;
  cloud.SetSchema(cloud.schema);
  const std::string path = dir.File("valid.las");
  WritePointCloud(path, cloud);
  return ReadBytes(path);
}

// ---- reading the shared real files ----

TEST(LasRead, SimpleLas) {
  CANDI_REQUIRE_SHARED_DATA(path, "las/simple.las");
  auto reader = OpenLasReader(path);
  const PointFileInfo& info = reader->info();
  EXPECT_EQ(info.count, 1065u);
  EXPECT_EQ(info.description, "LAS 1.2 point format 3");
  EXPECT_TRUE(info.meta.las.present);
  EXPECT_TRUE(info.schema.colors);
  ASSERT_GE(info.schema.ScalarIndex(las_field::kGpsTime), 0);
  EXPECT_EQ(info.schema.scalars[info.schema.ScalarIndex(las_field::kGpsTime)].type,
            ScalarType::kFloat64);
  EXPECT_FALSE(info.meta.las.color_16bit);  // values 0-249 stored in the 16-bit fields
  PointCloud cloud;
  ASSERT_EQ(reader->Read(1, &cloud), 1u);
  // First record, decoded independently: X Y Z 63701224 84902831 43166, scale 0.01.
  EXPECT_NEAR(cloud.positions[0].x(), 637012.24, 1e-9);
  EXPECT_NEAR(cloud.positions[0].y(), 849028.31, 1e-9);
  EXPECT_NEAR(cloud.positions[0].z(), 431.66, 1e-9);
  EXPECT_EQ(cloud.FindScalar(las_field::kIntensity)->Get(0), 143);
  EXPECT_EQ(cloud.FindScalar(las_field::kReturnNumber)->Get(0), 1);
  EXPECT_EQ(cloud.FindScalar(las_field::kNumberOfReturns)->Get(0), 1);
  EXPECT_EQ(cloud.FindScalar(las_field::kScanDirection)->Get(0), 1);
  EXPECT_EQ(cloud.FindScalar(las_field::kClassification)->Get(0), 1);
  EXPECT_EQ(cloud.FindScalar(las_field::kScanAngleRank)->Get(0), -9);
  EXPECT_EQ(cloud.FindScalar(las_field::kUserData)->Get(0), 132);
  EXPECT_EQ(cloud.FindScalar(las_field::kPointSourceId)->Get(0), 7326);
  EXPECT_EQ(cloud.FindScalar(las_field::kGpsTime)->Get(0), 245380.78254962614);
  EXPECT_EQ(cloud.colors[0], (Rgb8{68, 77, 88}));
  ExpectBoundsMatchHeader(path);
}

TEST(LasRead, AutzenTrimProjectedWithColours) {
  CANDI_REQUIRE_SHARED_DATA(path, "las/autzen_trim.las");
  const PointCloud cloud = ReadAll(path, 1 << 20);
  ASSERT_EQ(cloud.size(), 110000u);
  auto reader = OpenLasReader(path);
  const Box3d header = *reader->info().header_bounds;
  const Box3d bounds = cloud.WorldBounds();
  EXPECT_GE(bounds.min.x(), 635000.0);
  EXPECT_LE(bounds.max.x(), 639000.0);
  EXPECT_GE(bounds.min.y(), 848000.0);
  EXPECT_LE(bounds.max.y(), 854000.0);
  EXPECT_GE(bounds.min.x(), header.min.x() - 0.005);
  EXPECT_LE(bounds.max.x(), header.max.x() + 0.005);
  size_t non_black = 0;
  for (const Rgb8& c : cloud.colors) non_black += (c.r | c.g | c.b) != 0;
  EXPECT_GT(non_black, 100000u);
  // This trimmed autzen stores 8-bit values (max 236) in the 16-bit fields: detected as such.
  EXPECT_FALSE(cloud.meta.las.color_16bit);
  EXPECT_EQ(cloud.meta.las.vlrs.size(), 5u);
  ExpectBoundsMatchHeader(path);
}

TEST(LasRead, Simple14Format7With16BitColour) {
  CANDI_REQUIRE_SHARED_DATA(path, "las/simple1_4.las");
  const PointCloud cloud = ReadAll(path, 1 << 20);
  EXPECT_EQ(cloud.size(), 22600u);
  EXPECT_EQ(cloud.meta.las.version_minor, 4);
  EXPECT_EQ(cloud.meta.las.point_format, 7);
  EXPECT_TRUE(cloud.meta.las.color_16bit);  // values up to 65024
  EXPECT_GE(cloud.schema.ScalarIndex(las_field::kScannerChannel), 0);
  EXPECT_GE(cloud.schema.ScalarIndex(las_field::kScanAngle), 0);
  EXPECT_LT(cloud.schema.ScalarIndex(las_field::kScanAngleRank), 0);
  EXPECT_EQ(cloud.colors[0], (Rgb8{100, 104, 105}));  // 25600 26624 26880 >> 8
  ASSERT_EQ(cloud.meta.las.vlrs.size(), 3u);
  EXPECT_FALSE(cloud.meta.las.vlrs[1].extended);
  EXPECT_TRUE(cloud.meta.las.vlrs[2].extended);
  EXPECT_EQ(cloud.meta.las.vlrs[2].description, "WKT");
  ExpectBoundsMatchHeader(path);
}

TEST(LasRead, Format6WithEvlr) {
  CANDI_REQUIRE_SHARED_DATA(path, "las/1_4_w_evlr.las");
  const PointCloud cloud = ReadAll(path, 100);
  ASSERT_EQ(cloud.size(), 1000u);  // legacy count 0: the 64-bit count is used
  EXPECT_EQ(cloud.meta.las.point_format, 6);
  ASSERT_EQ(cloud.meta.las.vlrs.size(), 3u);
  const LasVlr& evlr = cloud.meta.las.vlrs[2];
  EXPECT_TRUE(evlr.extended);
  EXPECT_EQ(evlr.user_id, "pylastest");
  EXPECT_EQ(evlr.record_id, 42);
  EXPECT_EQ(evlr.data.size(), 16u);
  // First record: flags byte 72 = overlap flag (bit 3) and scan direction; class 2; angle 3005.
  EXPECT_EQ(cloud.FindScalar(las_field::kClassFlags)->Get(0), 8);
  EXPECT_EQ(cloud.FindScalar(las_field::kScanDirection)->Get(0), 1);
  EXPECT_EQ(cloud.FindScalar(las_field::kClassification)->Get(0), 2);
  EXPECT_EQ(cloud.FindScalar(las_field::kScanAngle)->Get(0), 3005);
  EXPECT_EQ(cloud.FindScalar(las_field::kPointSourceId)->Get(0), 202);
  EXPECT_EQ(cloud.FindScalar(las_field::kGpsTime)->Get(0), 83177420.53400505);
  ExpectBoundsMatchHeader(path);
}

TEST(LasRead, ReadsLaz) {  // more in io/laz/laz_test.cc
  CANDI_REQUIRE_SHARED_DATA(path, "las/autzen_trim.laz");
  auto reader = OpenPointReader(path);
  EXPECT_EQ(reader->info().format, PointFormat::kLas);
  EXPECT_EQ(reader->info().description.rfind("LAZ: ", 0), 0u) << reader->info().description;
  EXPECT_FALSE(reader->record_layout().has_value());
}

TEST(LasRead, StreamingInSmallChunksMatchesOneRead) {
  CANDI_REQUIRE_SHARED_DATA(path, "las/simple.las");
  ExpectSamePoints(ReadAll(path, 7), ReadAll(path, 1 << 20));
}

// ---- round trips ----

TEST(LasRoundTrip, SurveyScaleKeepsEveryAttribute) {
  TempDir dir;
  const PointCloud cloud = MakeSurveyCloud(5000);
  const std::string path = dir.File("survey.las");
  WritePointCloud(path, cloud);
  const PointCloud back = ReadAll(path, 1000);
  ASSERT_EQ(back.size(), cloud.size());
  EXPECT_EQ(back.meta.las.point_format, 3);  // colours and gps_time, no 1.4 attribute
  EXPECT_EQ(back.meta.las.offset, cloud.frame.origin);
  EXPECT_EQ(back.meta.las.scale, Eigen::Vector3d::Constant(0.001));
  ASSERT_TRUE(back.schema.normals);
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d d = back.WorldPosition(i) - cloud.WorldPosition(i);
    ASSERT_LE(d.cwiseAbs().maxCoeff(), 0.0005 + 1e-9) << "point " << i;
    ASSERT_EQ(back.colors[i], cloud.colors[i]);
    ASSERT_EQ(back.normals[i], cloud.normals[i]);
  }
  for (const char* name : {las_field::kIntensity, las_field::kClassification, las_field::kGpsTime,
                           "confidence", "range_m"}) {
    const ScalarField* a = cloud.FindScalar(name);
    const ScalarField* b = back.FindScalar(name);
    ASSERT_NE(b, nullptr) << name;
    EXPECT_EQ(b->spec.type, a->spec.type) << name;
    for (size_t i = 0; i < cloud.size(); ++i) ASSERT_EQ(b->Get(i), a->Get(i)) << name << " " << i;
  }
  EXPECT_EQ(back.FindScalar(las_field::kReturnNumber)->Get(0), 1);  // default: single return
}

TEST(LasRoundTrip, SurveyCoordinatesInFrameZeroGetAnOffset) {
  TempDir dir;
  PointCloud cloud = MakeSurveyCloud(100);
  cloud.Rebase(LocalFrame());  // world coordinates 4.5e6: no fit in int32 mm without an offset
  const std::string path = dir.File("zero.las");
  WritePointCloud(path, cloud);
  const PointCloud back = ReadAll(path, 1000);
  for (size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_LE((back.WorldPosition(i) - cloud.WorldPosition(i)).cwiseAbs().maxCoeff(),
              0.0005 + 1e-9);
  }
}

void ExpectRewriteIdentical(const std::string& source, bool compare_colour_bytes) {
  TempDir dir;
  const PointCloud cloud = ReadAll(source, 1 << 20);
  const std::string path = dir.File("rewrite.las");
  WritePointCloud(path, cloud);
  const PointCloud back = ReadAll(path, 1 << 20);
  EXPECT_EQ(back.meta.las.version_minor, cloud.meta.las.version_minor);
  EXPECT_EQ(back.meta.las.point_format, cloud.meta.las.point_format);
  EXPECT_EQ(back.meta.las.scale, cloud.meta.las.scale);
  EXPECT_EQ(back.meta.las.offset, cloud.meta.las.offset);
  EXPECT_EQ(back.meta.las.global_encoding, cloud.meta.las.global_encoding);
  ExpectSameVlrs(back.meta.las.vlrs, cloud.meta.las.vlrs);
  ExpectSamePoints(back, cloud);
  std::string a = LasPointRecords(ReadBytes(source)), b = LasPointRecords(ReadBytes(path));
  ASSERT_EQ(a.size(), b.size());
  if (!compare_colour_bytes) {  // 16-bit colour keeps only its high byte
    const size_t length = GetLE<uint16_t>(ReadBytes(source), 105);
    for (size_t i = 0; i < a.size(); i += length) {  // formats 7 and 8: colour at byte 30
      a.replace(i + 30, 6, 6, '\0');
      b.replace(i + 30, 6, 6, '\0');
    }
  }
  EXPECT_TRUE(a == b) << source << ": point records differ";
}

TEST(LasRoundTrip, RewritingSimpleLasKeepsRecordsByteExact) {
  CANDI_REQUIRE_SHARED_DATA(path, "las/simple.las");
  ExpectRewriteIdentical(path, true);
}

TEST(LasRoundTrip, RewritingFormat6KeepsEvlrAndRecords) {
  CANDI_REQUIRE_SHARED_DATA(path, "las/1_4_w_evlr.las");
  ExpectRewriteIdentical(path, true);
}

TEST(LasRoundTrip, RewritingFormat7KeepsRecordsButColourLowBytes) {
  CANDI_REQUIRE_SHARED_DATA(path, "las/simple1_4.las");
  ExpectRewriteIdentical(path, false);
}

TEST(LasRoundTrip, EvlrBecomesVlrInLas12) {
  CANDI_REQUIRE_SHARED_DATA(source, "las/1_4_w_evlr.las");
  TempDir dir;
  PointCloud cloud = ReadAll(source, 1 << 20);
  PointSchema schema = cloud.schema;  // without scanner_channel, LAS 1.2 can hold the points
  schema.scalars.erase(schema.scalars.begin() + schema.ScalarIndex(las_field::kScannerChannel));
  cloud.SetSchema(schema);
  PointWriteOptions options;
  options.las_version_minor = 2;
  const std::string path = dir.File("v12.las");
  WritePointCloud(path, cloud, options);
  const PointCloud back = ReadAll(path, 1 << 20);
  EXPECT_EQ(back.meta.las.version_minor, 2);
  EXPECT_EQ(back.meta.las.point_format, 1);  // gps_time, no colour
  ASSERT_EQ(back.meta.las.vlrs.size(), 3u);
  EXPECT_EQ(back.meta.las.vlrs[2].user_id, "pylastest");
  EXPECT_FALSE(back.meta.las.vlrs[2].extended);
  EXPECT_EQ(back.meta.las.vlrs[2].data, cloud.meta.las.vlrs[2].data);
  EXPECT_EQ(back.meta.las.global_encoding, 1);  // GPS time type kept, WKT bit is 1.4 only
  // The scan angle (0.006 degree units) becomes the rank in degrees: 3005 -> 18.
  EXPECT_EQ(back.FindScalar(las_field::kScanAngleRank)->Get(0), 18);
  for (size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_EQ(back.WorldPosition(i), cloud.WorldPosition(i));
    ASSERT_EQ(back.FindScalar(las_field::kGpsTime)->Get(i),
              cloud.FindScalar(las_field::kGpsTime)->Get(i));
  }
}

TEST(LasRoundTrip, ChunksInOtherFramesAreReexpressed) {
  TempDir dir;
  const PointCloud cloud = MakeSurveyCloud(200);
  PointCloud shifted = cloud;
  shifted.Rebase(LocalFrame{Eigen::Vector3d(499000.0, 4501000.0, 50.0)});
  const std::string path = dir.File("frames.las");
  auto writer = OpenLasWriter(path, {cloud.schema, cloud.frame, cloud.meta, 400}, {});
  writer->Write(cloud);
  writer->Write(shifted);
  writer->Close();
  const PointCloud back = ReadAll(path, 1000);
  ASSERT_EQ(back.size(), 400u);
  for (size_t i = 0; i < 200; ++i) {
    ASSERT_EQ(back.WorldPosition(i), back.WorldPosition(200 + i)) << i;
    ASSERT_LE((back.WorldPosition(i) - cloud.WorldPosition(i)).cwiseAbs().maxCoeff(),
              0.0005 + 1e-9);
  }
}

TEST(LasRoundTrip, EightBitColourInSixteenBitFieldsIsByteExact) {
  TempDir dir;
  PointCloud cloud = MakeSurveyCloud(300);
  cloud.meta.las.color_16bit = false;
  const std::string first = dir.File("a.las"), second = dir.File("b.las");
  WritePointCloud(first, cloud);
  const std::string bytes = ReadBytes(first);
  const size_t offset = GetLE<uint32_t>(bytes, 96), length = GetLE<uint16_t>(bytes, 105);
  // Format 3 red of point 5: 5, not 5*257.
  EXPECT_EQ(GetLE<uint16_t>(bytes, offset + 5 * length + 28), 5);
  const PointCloud back = ReadAll(first, 64);
  EXPECT_FALSE(back.meta.las.color_16bit);
  for (size_t i = 0; i < cloud.size(); ++i) ASSERT_EQ(back.colors[i], cloud.colors[i]);
  WritePointCloud(second, back);
  const std::string a = LasPointRecords(bytes), b = LasPointRecords(ReadBytes(second));
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); i += length) ASSERT_EQ(a.substr(i + 28, 6), b.substr(i + 28, 6));
}

TEST(LasRoundTrip, SixteenBitColourIsScaledAndDetected) {
  TempDir dir;
  const PointCloud cloud = MakeSurveyCloud(300);  // meta.las.color_16bit defaults to true
  const std::string path = dir.File("c.las");
  WritePointCloud(path, cloud);
  const std::string bytes = ReadBytes(path);
  const size_t offset = GetLE<uint32_t>(bytes, 96), length = GetLE<uint16_t>(bytes, 105);
  EXPECT_EQ(GetLE<uint16_t>(bytes, offset + 5 * length + 28), 5 * 257);
  const PointCloud back = ReadAll(path, 1000);
  EXPECT_TRUE(back.meta.las.color_16bit);
  for (size_t i = 0; i < cloud.size(); ++i) ASSERT_EQ(back.colors[i], cloud.colors[i]);
}

TEST(LasRoundTrip, ExtraBytesOfIntegerTypeWithScaleAndUndocumentedBytes) {
  TempDir dir;
  const PointCloud cloud =
      MakePlainCloud(20, {{"v", ScalarType::kFloat32}, {"w", ScalarType::kFloat32}});
  const std::string path = dir.File("extra.las");
  WritePointCloud(path, cloud);
  std::string bytes = ReadBytes(path);
  // Format 0, one VLR (extra bytes) right after the 227-byte header: descriptors at 227 + 54.
  ASSERT_EQ(bytes[104], 0);
  const size_t v = 227 + 54, w = v + 192;
  bytes[v + 2] = 6;     // long (int32)
  bytes[v + 3] = 0x18;  // scale and offset valid
  PutLE<double>(&bytes, v + 112, 0.5);
  PutLE<double>(&bytes, v + 136, 10.0);
  bytes[w + 2] = 0;  // undocumented extra bytes
  bytes[w + 3] = 4;  // of length 4
  const size_t offset = GetLE<uint32_t>(bytes, 96), length = GetLE<uint16_t>(bytes, 105);
  ASSERT_EQ(length, 28u);
  for (size_t i = 0; i < 20; ++i)
    PutLE<int32_t>(&bytes, offset + i * length + 20, 3 * int32_t(i) - 7);
  WriteBytes(path, bytes);
  const PointCloud back = ReadAll(path, 8);
  EXPECT_LT(back.schema.ScalarIndex("w"), 0);
  const ScalarField* field = back.FindScalar("v");
  ASSERT_NE(field, nullptr);
  EXPECT_EQ(field->spec.type, ScalarType::kFloat64);
  for (size_t i = 0; i < 20; ++i) EXPECT_EQ(field->Get(i), (3.0 * i - 7) * 0.5 + 10.0);
}

// ---- version and format choice ----

std::string WriteAndDescribe(const TempDir& dir, const PointCloud& cloud,
                             const PointWriteOptions& options = {}) {
  const std::string path = dir.File("choice.las");
  WritePointCloud(path, cloud, options);
  return OpenLasReader(path)->info().description;
}

TEST(LasWrite, ChoosesTheSmallestFittingFormat) {
  TempDir dir;
  EXPECT_EQ(WriteAndDescribe(dir, MakePlainCloud(5)), "LAS 1.2 point format 0");
  EXPECT_EQ(WriteAndDescribe(dir, MakePlainCloud(5, {{las_field::kGpsTime, ScalarType::kFloat64}})),
            "LAS 1.2 point format 1");
  EXPECT_EQ(WriteAndDescribe(dir, MakeSurveyCloud(5)), "LAS 1.2 point format 3");
  EXPECT_EQ(WriteAndDescribe(
                dir, MakePlainCloud(5, {{las_field::kScannerChannel, ScalarType::kFloat32}})),
            "LAS 1.4 point format 6");
  PointCloud nir = MakePlainCloud(5, {{las_field::kNir, ScalarType::kFloat32}});
  EXPECT_EQ(WriteAndDescribe(dir, nir), "LAS 1.4 point format 8");
}

TEST(LasWrite, ExplicitFormatsAreValidated) {
  TempDir dir;
  PointWriteOptions options;
  options.las_point_format = 1;
  try {
    WriteAndDescribe(dir, MakeSurveyCloud(5), options);
    FAIL() << "format 1 accepted colours";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("las_point_format"), std::string::npos) << e.what();
  }
  options.las_point_format = 7;
  options.las_version_minor = 2;
  try {
    WriteAndDescribe(dir, MakeSurveyCloud(5), options);
    FAIL() << "format 7 accepted in LAS 1.2";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("las_version_minor"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(FileExists(dir.File("choice.las")));
  options.las_point_format = -1;
  options.las_version_minor = 4;
  EXPECT_EQ(WriteAndDescribe(dir, MakeSurveyCloud(5), options), "LAS 1.4 point format 3");
  const std::string bytes = ReadBytes(dir.File("choice.las"));
  EXPECT_EQ(GetLE<uint32_t>(bytes, 107), 5u);  // legacy count kept for formats 0-5
  EXPECT_EQ(GetLE<uint64_t>(bytes, 247), 5u);  // and the 64-bit count
  EXPECT_EQ(GetLE<uint64_t>(bytes, 255), 5u);  // 5 first returns
}

TEST(LasWrite, ScanAngleConvertsBetweenFormats) {
  TempDir dir;
  PointCloud cloud = MakePlainCloud(3, {{las_field::kScanAngleRank, ScalarType::kFloat32}});
  cloud.scalars[0].f32 = {-12.0f, 0.0f, 30.0f};
  PointWriteOptions options;
  options.las_point_format = 6;
  WriteAndDescribe(dir, cloud, options);
  const PointCloud back = ReadAll(dir.File("choice.las"), 10);
  const ScalarField* angle = back.FindScalar(las_field::kScanAngle);
  ASSERT_NE(angle, nullptr);
  EXPECT_EQ(angle->Get(0), -2000);  // -12 degrees in 0.006 degree units
  EXPECT_EQ(angle->Get(2), 5000);
  EXPECT_LT(back.schema.ScalarIndex(las_field::kScanAngleRank),
            0);  // not duplicated as extra bytes
}

TEST(LasHeader, CountFieldsFollowVersionAndFormat) {
  std::array<uint64_t, 15> by_return{};
  by_return[0] = 5000000000ull;
  LasHeader header;
  header.version_minor = 4;
  header.point_format = 6;
  ASSERT_TRUE(SetLasCounts(5000000000ull, by_return, &header));
  EXPECT_EQ(header.legacy_count, 0u);
  EXPECT_EQ(header.count, 5000000000ull);
  EXPECT_EQ(LasPointCount(header), 5000000000ull);
  header.point_format = 1;  // legacy format in 1.4, count too large for 32 bits
  ASSERT_TRUE(SetLasCounts(5000000000ull, by_return, &header));
  EXPECT_EQ(header.legacy_count, 0u);
  EXPECT_EQ(header.legacy_by_return[0], 0u);
  by_return[0] = 7;
  ASSERT_TRUE(SetLasCounts(10, by_return, &header));
  EXPECT_EQ(header.legacy_count, 10u);
  EXPECT_EQ(header.legacy_by_return[0], 7u);
  header.version_minor = 2;
  EXPECT_FALSE(SetLasCounts(5000000000ull, by_return, &header));
  EXPECT_TRUE(SetLasCounts(10, by_return, &header));
  EXPECT_EQ(LasPointCount(header), 10u);
  header.legacy_count = 0;
  header.count = 99;  // the 64-bit field means nothing before 1.4
  EXPECT_EQ(LasPointCount(header), 0u);
}

// ---- bad input ----

TEST(LasBadInput, TruncatedFileNamesTheBytePosition) {
  TempDir dir;
  const std::string bytes = ValidSmallLas(dir);
  const std::string path = dir.File("truncated.las");
  WriteBytes(path, bytes.substr(0, bytes.size() - 40));
  const std::string error = InputErrorMessage([&] { OpenLasReader(path); });
  EXPECT_NE(error.find("byte " + std::to_string(bytes.size() - 40)), std::string::npos) << error;
  EXPECT_NE(error.find("promises 10 points"), std::string::npos) << error;
}

// Issue 9's limit: a header claiming 10^12 points is refused against the file size at open,
// before anything is allocated or read.
TEST(LasBadInput, HeaderClaimingTenToTheTwelvePointsIsRefusedAtOpen) {
  TempDir dir;
  PointCloud cloud = MakePlainCloud(10, {});
  const std::string path = dir.File("huge.las");
  PointWriteOptions options;
  options.las_version_minor = 4;
  options.las_point_format = 6;
  WritePointCloud(path, cloud, options);
  std::string bytes = ReadBytes(path);
  const uint64_t claimed = 1000000000000ull;
  bytes.replace(247, 8, reinterpret_cast<const char*>(&claimed), 8);  // LAS 1.4 64-bit count
  WriteBytes(path, bytes);
  const std::string error = InputErrorMessage([&] { OpenLasReader(path); });
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("promises 1000000000000 points"), std::string::npos) << error;
  EXPECT_NE(error.find("byte " + std::to_string(bytes.size())), std::string::npos) << error;
}

TEST(LasBadInput, HeaderDefectsAreReported) {
  TempDir dir;
  const std::string valid = ValidSmallLas(dir);
  const std::string path = dir.File("bad.las");
  auto error_after = [&](const std::function<void(std::string*)>& patch) {
    std::string bytes = valid;
    patch(&bytes);
    WriteBytes(path, bytes);
    return InputErrorMessage([&] { OpenLasReader(path); });
  };
  EXPECT_NE(error_after([](std::string* b) { (*b)[0] = 'X'; }).find("LASF"), std::string::npos);
  const std::string format = error_after([](std::string* b) { (*b)[104] = 4; });
  EXPECT_NE(format.find("point format 4"), std::string::npos) << format;
  EXPECT_NE(error_after([](std::string* b) { (*b)[104] = 9; }).find("point format 9"),
            std::string::npos);
  const std::string length = error_after([](std::string* b) { PutLE<uint16_t>(b, 105, 20); });
  EXPECT_NE(length.find("record length 20"), std::string::npos) << length;
  const std::string scale = error_after([](std::string* b) { PutLE<double>(b, 139, 0.0); });
  EXPECT_NE(scale.find("scale"), std::string::npos) << scale;
  EXPECT_NE(error_after([](std::string* b) { (*b)[104] |= 0x80; }).find("LAZ"), std::string::npos);
  EXPECT_NE(error_after([](std::string* b) { b->resize(100); }).find("header"), std::string::npos);
  EXPECT_NE(error_after([](std::string* b) { b->clear(); }).find("empty"), std::string::npos);
  EXPECT_NE(error_after([](std::string* b) { PutLE<uint32_t>(b, 96, 1u << 30); }).find("offset"),
            std::string::npos);
}

TEST(LasBadInput, OverrunningVlrIsReported) {
  TempDir dir;
  const std::string valid = ValidSmallLas(dir);
  std::string bytes = valid;
  PutLE<uint32_t>(&bytes, 100, 1);  // one VLR, but the points start right after the header
  const std::string path = dir.File("vlr.las");
  WriteBytes(path, bytes);
  EXPECT_NE(InputErrorMessage([&] { OpenLasReader(path); }).find("VLR"), std::string::npos);
}

TEST(LasBadInput, EvlrBeyondTheFileIsReported) {
  CANDI_REQUIRE_SHARED_DATA(source, "las/1_4_w_evlr.las");
  TempDir dir;
  std::string bytes = ReadBytes(source);
  PutLE<uint64_t>(&bytes, 235, bytes.size() + 100);  // start of the first EVLR
  const std::string path = dir.File("evlr.las");
  WriteBytes(path, bytes);
  const std::string error = InputErrorMessage([&] { OpenLasReader(path); });
  EXPECT_NE(error.find("byte " + std::to_string(bytes.size() + 100)), std::string::npos) << error;
}

// ---- writer failures ----

TEST(LasWrite, MissingFolderCreatesNothing) {
  TempDir dir;
  const std::string folder = dir.File("no_such_folder");
  EXPECT_THROW(WritePointCloud(folder + "/out.las", MakeSurveyCloud(10)), InputError);
  EXPECT_FALSE(FileExists(folder));
}

TEST(LasWrite, DestroyedWriterLeavesTheDestinationIntact) {
  TempDir dir;
  const std::string path = dir.File("keep.las");
  WritePointCloud(path, MakeSurveyCloud(50));
  const std::string before = ReadBytes(path);
  {
    const PointCloud other = MakeSurveyCloud(80);
    auto writer = OpenLasWriter(path, {other.schema, other.frame, other.meta, other.size()}, {});
    writer->Write(other);
  }
  EXPECT_EQ(ReadBytes(path), before);
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()),
                          std::filesystem::directory_iterator()),
            1);  // no temporary left behind
}

TEST(LasWrite, CoordinateOutsideInt32IsAnInputError) {
  TempDir dir;
  PointCloud cloud = MakePlainCloud(3);
  cloud.positions[2] = Eigen::Vector3d(1.0e7, 0.0, 0.0);
  PointWriteOptions options;
  options.las_scale = Eigen::Vector3d::Constant(0.001);
  options.las_offset = Eigen::Vector3d::Zero();
  const std::string path = dir.File("far.las");
  const std::string error = InputErrorMessage([&] { WritePointCloud(path, cloud, options); });
  EXPECT_NE(error.find("point 2"), std::string::npos) << error;
  EXPECT_NE(error.find("does not fit LAS int32"), std::string::npos) << error;
  EXPECT_FALSE(FileExists(path));
}

TEST(LasWrite, ChunkSchemaMustMatchSpec) {
  TempDir dir;
  const PointCloud cloud = MakeSurveyCloud(4);
  auto writer = OpenLasWriter(dir.File("s.las"), {cloud.schema, cloud.frame, cloud.meta, 4}, {});
  EXPECT_THROW(writer->Write(MakePlainCloud(4)), InternalError);
}

}  // namespace
}  // namespace candi::io

#include "io/e57/e57_io.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <random>

#include "core/check.h"
#include "io/e57/e57_format.h"
#include "io/e57/e57_writer.h"
#include "io/point_io.h"
#include "tests/util/input_error.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using testing::ReadBytes;
using testing::TempDir;
using testing::WriteBytes;

std::string DataFile(const std::string& name) {
  return testing::SourceDir() + "/tests/data/e57/" + name;
}

// The error message of reading `path` entirely, "" when it reads.
std::string ReadError(const std::string& path) {
  return testing::InputErrorMessage([&] { ReadPointCloud(path); });
}

E57Field Field(const std::string& name, E57FieldType type, std::vector<double> values,
               int64_t lo = 0, int64_t hi = 0, double scale = 1.0, double offset = 0.0) {
  E57Field f;
  f.name = name;
  f.type = type;
  f.values = std::move(values);
  f.minimum = lo, f.maximum = hi;
  f.scale = scale, f.offset = offset;
  return f;
}

E57Scan CartesianScan(const std::vector<Eigen::Vector3d>& p, E57FieldType type) {
  E57Scan scan;
  const char* names[3] = {"cartesianX", "cartesianY", "cartesianZ"};
  for (int k = 0; k < 3; ++k) {
    std::vector<double> v;
    for (const auto& q : p) v.push_back(q[k]);
    scan.fields.push_back(Field(names[k], type, v));
  }
  return scan;
}

std::vector<Eigen::Vector3d> RandomPoints(size_t n, double extent, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-extent, extent);
  std::vector<Eigen::Vector3d> p(n);
  for (auto& q : p) q = Eigen::Vector3d(u(rng), u(rng), u(rng));
  return p;
}

// Replaces `from` by `to` in the XML of an E57 file, re-paging the file with fresh CRCs (for
// building bad inputs that get past the CRC check).
void RewriteXml(const std::string& path, const std::string& from, const std::string& to) {
  std::string bytes = ReadBytes(path);
  std::string logical;
  for (size_t i = 0; i < bytes.size(); i += e57::kPageSize) logical += bytes.substr(i, e57::kPageData);
  uint64_t xml_offset, xml_length;
  std::memcpy(&xml_offset, logical.data() + 24, 8);
  std::memcpy(&xml_length, logical.data() + 32, 8);
  const uint64_t at = e57::LogicalOf(xml_offset);
  std::string xml = logical.substr(at, xml_length);
  const size_t hit = xml.find(from);
  CANDI_CHECK(hit != std::string::npos) << from;
  xml.replace(hit, from.size(), to);
  logical = logical.substr(0, at) + xml;
  const uint64_t length = xml.size();
  std::memcpy(&logical[32], &length, 8);
  logical.resize((logical.size() + e57::kPageData - 1) / e57::kPageData * e57::kPageData, '\0');
  const uint64_t physical = logical.size() / e57::kPageData * e57::kPageSize;
  std::memcpy(&logical[16], &physical, 8);
  std::string out;
  for (size_t i = 0; i < logical.size(); i += e57::kPageData) {
    const std::string page = logical.substr(i, e57::kPageData);
    const uint32_t crc = e57::Crc32c(page.data(), page.size());
    out += page;
    for (int s = 24; s >= 0; s -= 8) out += static_cast<char>((crc >> s) & 0xFF);
  }
  WriteBytes(path, out);
}

// ---- CRC-32C ----

TEST(E57Crc32c, KnownAnswer) {
  EXPECT_EQ(e57::Crc32cPortable("123456789", 9), 0xE3069283u);
  EXPECT_EQ(e57::Crc32c("123456789", 9), 0xE3069283u);
  if (e57::HasCrc32cInstruction()) {
    EXPECT_EQ(e57::Crc32cHardware("123456789", 9), 0xE3069283u);
  }
}

TEST(E57Crc32c, HardwareMatchesTable) {
  if (!e57::HasCrc32cInstruction()) GTEST_SKIP() << "no SSE4.2 crc32 instruction on this CPU";
  std::mt19937 rng(7);
  std::vector<uint8_t> data(3000);
  for (auto& b : data) b = static_cast<uint8_t>(rng());
  for (size_t n : {0, 1, 7, 8, 9, 1020, 2999}) {
    for (size_t start : {0, 1, 3}) {
      EXPECT_EQ(e57::Crc32cHardware(data.data() + start, n), e57::Crc32cPortable(data.data() + start, n))
          << n << " bytes from " << start;
    }
  }
}

TEST(E57Paged, LogicalPhysical) {
  EXPECT_EQ(e57::PhysicalOf(0), 0u);
  EXPECT_EQ(e57::PhysicalOf(1019), 1019u);
  EXPECT_EQ(e57::PhysicalOf(1020), 1024u);
  EXPECT_EQ(e57::LogicalOf(2048 + 5), 2040u + 5);
  for (uint64_t l : {0ull, 1ull, 1019ull, 1020ull, 123456789ull}) EXPECT_EQ(e57::LogicalOf(e57::PhysicalOf(l)), l);
  EXPECT_EQ(e57::BitsForRange(0, 0), 0);
  EXPECT_EQ(e57::BitsForRange(0, 1), 1);
  EXPECT_EQ(e57::BitsForRange(0, 255), 8);
  EXPECT_EQ(e57::BitsForRange(-500, 500), 10);
  EXPECT_EQ(e57::BitsForRange(INT64_MIN, INT64_MAX), 64);
}

// ---- Real files ----

TEST(E57Io, ReadsColouredCubeFloat) {
  const std::string path = DataFile("ColouredCubeFloat.e57");
  EXPECT_EQ(DetectPointFormat(path), PointFormat::kE57);
  auto reader = OpenPointReader(path);
  EXPECT_EQ(reader->info().format, PointFormat::kE57);
  EXPECT_EQ(reader->info().count, 7680u);
  EXPECT_TRUE(reader->info().schema.colors);
  EXPECT_NE(reader->info().description.find("E57 1.0, 1 scan (cartesian float), 7680 points"),
            std::string::npos)
      << reader->info().description;
  const PointCloud cloud = ReadPointCloud(path);
  ASSERT_EQ(cloud.size(), 7680u);
  const Box3d box = cloud.WorldBounds();
  EXPECT_GE(box.min.minCoeff(), -0.5);
  EXPECT_LE(box.max.maxCoeff(), 0.5);
  EXPECT_GT(box.max.x() - box.min.x(), 0.9);
  int distinct = 0;
  for (size_t i = 1; i < cloud.size(); ++i) distinct += !(cloud.colors[i] == cloud.colors[0]);
  EXPECT_GT(distinct, 100);
}

TEST(E57Io, ReadsBunnyScaledIntegers) {
  const std::string path = DataFile("bunnyInt32.e57");
  auto reader = OpenE57Reader(path);
  EXPECT_EQ(reader->info().count, kUnknownCount);  // cartesianInvalidState may drop points
  EXPECT_FALSE(reader->info().schema.colors);
  EXPECT_EQ(reader->info().meta.comments.at(0), "e57 scan 0: bunny");
  const PointCloud cloud = ReadPointCloud(path);
  EXPECT_GT(cloud.size(), 30000u);
  EXPECT_LE(cloud.size(), 30571u);
  const Box3d box = cloud.WorldBounds();  // cartesianBounds in the XML
  EXPECT_NEAR(box.min.x(), -0.094689, 1e-6);
  EXPECT_NEAR(box.max.x(), 0.061009, 1e-6);
  EXPECT_NEAR(box.min.y(), 0.040011, 1e-6);
  EXPECT_NEAR(box.max.y(), 0.187321, 1e-6);
  EXPECT_NEAR(box.min.z(), -0.061873, 1e-6);
  EXPECT_NEAR(box.max.z(), 0.058799, 1e-6);
}

TEST(E57Io, ReadsLas2e57Output) {
  const PointCloud cloud = ReadPointCloud(DataFile("ColourRepresentation.e57"));
  ASSERT_EQ(cloud.size(), 153u);
  EXPECT_TRUE(cloud.schema.colors);
  const Box3d box = cloud.WorldBounds();
  EXPECT_NEAR(box.min.minCoeff(), -0.5, 1e-9);
  EXPECT_NEAR(box.max.maxCoeff(), 0.5, 1e-9);
}

TEST(E57Io, BadCrcNamesTheByte) {
  const std::string path = DataFile("bad-crc.e57");
  const std::string error = ReadError(path);
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("byte 0"), std::string::npos) << error;
  EXPECT_NE(error.find("CRC-32C mismatch"), std::string::npos) << error;
}

// ---- Round trips ----

TEST(E57Io, ScansLandInTheFileFrame) {
  TempDir dir;
  const std::string path = dir.File("posed.e57");
  const auto a = RandomPoints(500, 10.0, 1), b = RandomPoints(300, 5.0, 2);
  E57Scan s0 = CartesianScan(a, E57FieldType::kDouble);
  s0.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  s0.translation = Eigen::Vector3d(100, -20, 3.5);
  E57Scan s1 = CartesianScan(b, E57FieldType::kFloat);
  s1.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(-1.2, Eigen::Vector3d::UnitZ()));
  s1.translation = Eigen::Vector3d(-7, 8, 9);
  s1.name = "second";
  WriteE57(path, {s0, s1});
  auto reader = OpenE57Reader(path);
  EXPECT_EQ(reader->info().count, 800u);
  EXPECT_NE(reader->info().description.find("2 scans (cartesian double, cartesian float)"),
            std::string::npos)
      << reader->info().description;
  EXPECT_EQ(reader->info().meta.comments.at(1), "e57 scan 1: second");
  const PointCloud cloud = ReadPointCloud(path);
  ASSERT_EQ(cloud.size(), 800u);
  for (size_t i = 0; i < a.size(); ++i) {
    const Eigen::Vector3d want = s0.rotation.toRotationMatrix() * a[i] + s0.translation;
    ASSERT_LT((cloud.WorldPosition(i) - want).norm(), 1e-9) << i;
  }
  for (size_t i = 0; i < b.size(); ++i) {
    const Eigen::Vector3d want = s1.rotation.toRotationMatrix() * b[i].cast<float>().cast<double>() +
                                 s1.translation;
    ASSERT_LT((cloud.WorldPosition(a.size() + i) - want).norm(), 1e-9) << i;
  }
}

TEST(E57Io, OneScanInItsOwnFrameAndThePosesListed) {
  TempDir dir;
  const std::string path = dir.File("two.e57");
  const auto a = RandomPoints(200, 10.0, 5), b = RandomPoints(100, 5.0, 6);
  E57Scan s0 = CartesianScan(a, E57FieldType::kDouble);
  s0.translation = Eigen::Vector3d(416000, 9168000, 100);
  E57Scan s1 = CartesianScan(b, E57FieldType::kDouble);
  s1.rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
  s1.translation = Eigen::Vector3d(416010, 9168005, 101);
  s1.name = "station 2";
  WriteE57(path, {s0, s1});
  const std::vector<E57ScanInfo> scans = ListE57Scans(path);
  ASSERT_EQ(scans.size(), 2u);
  EXPECT_EQ(scans[1].name, "station 2");
  EXPECT_EQ(scans[1].records, 100u);
  EXPECT_EQ(scans[0].translation, s0.translation);
  EXPECT_LT(scans[1].rotation.angularDistance(s1.rotation), 1e-12);
  PointCloud one;
  auto reader = OpenE57ScanReader(path, 1);
  EXPECT_EQ(reader->info().count, 100u);
  reader->Read(1000, &one);
  ASSERT_EQ(one.size(), 100u);
  for (size_t i = 0; i < b.size(); ++i) ASSERT_LT((one.WorldPosition(i) - b[i]).norm(), 1e-12) << i;
  try {
    OpenE57ScanReader(path, 2);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no scan 2"), std::string::npos) << e.what();
  }
}

TEST(E57Io, SphericalWithInvalidPointsDropped) {
  TempDir dir;
  const std::string path = dir.File("spherical.e57");
  std::vector<double> r, az, el, state;
  for (int i = 0; i < 1000; ++i) {
    r.push_back(1.0 + i * 0.01);
    az.push_back(-3.0 + i * 0.006);
    el.push_back(-1.5 + i * 0.003);
    state.push_back(i % 7 == 0 ? 2 : i % 11 == 0 ? 1 : 0);
  }
  E57Scan scan;
  scan.fields = {Field("sphericalRange", E57FieldType::kDouble, r),
                 Field("sphericalAzimuth", E57FieldType::kFloat, az),
                 Field("sphericalElevation", E57FieldType::kDouble, el),
                 Field("sphericalInvalidState", E57FieldType::kInteger, state, 0, 2)};
  scan.translation = Eigen::Vector3d(1, 2, 3);
  WriteE57(path, {scan});
  auto reader = OpenE57Reader(path);
  EXPECT_EQ(reader->info().count, kUnknownCount);
  const PointCloud cloud = ReadPointCloud(path);
  size_t j = 0;
  for (int i = 0; i < 1000; ++i) {
    if (state[i] != 0) continue;
    const double a = static_cast<float>(az[i]);
    const Eigen::Vector3d want(r[i] * std::cos(el[i]) * std::cos(a),
                               r[i] * std::cos(el[i]) * std::sin(a), r[i] * std::sin(el[i]));
    ASSERT_LT(j, cloud.size());
    ASSERT_LT((cloud.WorldPosition(j) - want - scan.translation).norm(), 1e-12) << i;
    ++j;
  }
  EXPECT_EQ(j, cloud.size());
}

// Odd bit widths (13 and 33 bits) straddle bytes, words and packets (7 records a packet).
TEST(E57Io, BitPackingAcrossBufferBoundaries) {
  TempDir dir;
  const std::string path = dir.File("bits.e57");
  std::mt19937_64 rng(3);
  std::vector<double> x, y, z, intensity, red, green, blue;
  for (int i = 0; i < 2000; ++i) {
    x.push_back(static_cast<double>(static_cast<int64_t>(rng() % 8000) - 4000));       // 13 bits
    y.push_back(static_cast<double>(static_cast<int64_t>(rng() % (1ull << 33)) - 5));  // 33 bits
    z.push_back(static_cast<double>(rng() % 100000) * 0.001 - 20.0);
    intensity.push_back(static_cast<double>(rng() % 4096));
    red.push_back(static_cast<double>(rng() % 1024));
    green.push_back(0);
    blue.push_back(1023);
  }
  E57Scan scan;
  scan.fields = {Field("cartesianX", E57FieldType::kInteger, x, -4096, 4095),
                 Field("cartesianY", E57FieldType::kInteger, y, -5, (1ll << 33) - 6),
                 Field("cartesianZ", E57FieldType::kScaledInteger, z, -20000, 80000, 0.001),
                 Field("intensity", E57FieldType::kInteger, intensity, 0, 4095),
                 Field("colorRed", E57FieldType::kInteger, red, 0, 1023),
                 Field("colorGreen", E57FieldType::kInteger, green, 0, 1023),
                 Field("colorBlue", E57FieldType::kInteger, blue, 0, 1023)};
  scan.intensity_limits = Eigen::Vector2d(0, 4095);
  scan.color_limits = Eigen::Vector2d(0, 1023);
  for (size_t packet : {7, 0}) {
    E57WriteOptions options;
    options.packet_records = packet;
    WriteE57(path, {scan}, options);
    const PointCloud cloud = ReadPointCloud(path);
    ASSERT_EQ(cloud.size(), 2000u);
    const ScalarField* s = cloud.FindScalar("intensity");
    ASSERT_NE(s, nullptr);
    for (size_t i = 0; i < 2000; ++i) {
      ASSERT_EQ(cloud.positions[i].x(), x[i]) << i;
      ASSERT_EQ(cloud.positions[i].y(), y[i]) << i;
      ASSERT_NEAR(cloud.positions[i].z(), z[i], 1e-9) << i;
      ASSERT_EQ(s->Get(i), intensity[i]) << i;
      ASSERT_EQ(cloud.colors[i].r, static_cast<uint8_t>(std::nearbyint(red[i] * 255.0 / 1023.0)));
      ASSERT_EQ(cloud.colors[i].g, 0);
      ASSERT_EQ(cloud.colors[i].b, 255);
    }
  }
}

TEST(E57Io, ZeroBitFieldsAndColorLimitsFromFields) {
  TempDir dir;
  const std::string path = dir.File("zero.e57");
  E57Scan scan;
  scan.fields = {Field("cartesianX", E57FieldType::kInteger, {5, 5, 5}, 5, 5),
                 Field("cartesianY", E57FieldType::kScaledInteger, {0.5, 1.0, 1.5}, 0, 3, 0.5),
                 Field("cartesianZ", E57FieldType::kFloat, {1, 2, 3}),
                 Field("colorRed", E57FieldType::kInteger, {0, 100, 200}, 0, 200),
                 Field("colorGreen", E57FieldType::kInteger, {7, 7, 7}, 7, 7),
                 Field("colorBlue", E57FieldType::kInteger, {0, 1, 0}, 0, 1)};
  WriteE57(path, {scan});
  const PointCloud cloud = ReadPointCloud(path);
  ASSERT_EQ(cloud.size(), 3u);
  EXPECT_EQ(cloud.positions[2], Eigen::Vector3d(5, 1.5, 3));
  EXPECT_EQ(cloud.colors[1].r, 128);  // 100 of 0..200
  EXPECT_EQ(cloud.colors[1].b, 255);
}

TEST(E57Io, LargeCoordinatesExactWithScaledIntegers) {
  TempDir dir;
  const std::string path = dir.File("survey.e57");
  std::vector<double> x, y, z;
  for (int i = 0; i < 1000; ++i) {
    x.push_back(1e6 + i * 0.0001);
    y.push_back(5e6 - i * 0.0013);
    z.push_back(250.0 + i * 0.0007);
  }
  E57Scan scan;
  const int64_t big = int64_t{1} << 40;
  scan.fields = {Field("cartesianX", E57FieldType::kScaledInteger, x, -big, big, 1e-4),
                 Field("cartesianY", E57FieldType::kScaledInteger, y, -big, big, 1e-4),
                 Field("cartesianZ", E57FieldType::kScaledInteger, z, -big, big, 1e-4)};
  WriteE57(path, {scan});
  const PointCloud cloud = ReadPointCloud(path);
  ASSERT_EQ(cloud.size(), 1000u);
  for (int i = 0; i < 1000; ++i) {
    ASSERT_NEAR(cloud.WorldPosition(i).x(), x[i], 1e-9);
    ASSERT_NEAR(cloud.WorldPosition(i).y(), y[i], 1e-9);
    ASSERT_NEAR(cloud.WorldPosition(i).z(), z[i], 1e-9);
  }
}

TEST(E57Io, EmptyScansAndCoordinateMetadata) {
  TempDir dir;
  const std::string path = dir.File("empty.e57");
  E57WriteOptions options;
  options.coordinate_metadata = "PROJCS[\"ETRS89 / UTM 32N\"]]>odd";
  E57Scan empty = CartesianScan({}, E57FieldType::kFloat);
  E57Scan one = CartesianScan({Eigen::Vector3d(1, 2, 3)}, E57FieldType::kFloat);
  WriteE57(path, {empty, one, empty}, options);
  auto reader = OpenE57Reader(path);
  EXPECT_EQ(reader->info().count, 1u);
  EXPECT_EQ(reader->info().meta.crs, options.coordinate_metadata);
  const PointCloud cloud = ReadPointCloud(path);
  ASSERT_EQ(cloud.size(), 1u);
  EXPECT_EQ(cloud.positions[0], Eigen::Vector3d(1, 2, 3));
  WriteE57(path, {}, options);
  EXPECT_EQ(ReadPointCloud(path).size(), 0u);
}

TEST(E57Io, MixedScansGetDefaultColorAndZeroIntensity) {
  TempDir dir;
  const std::string path = dir.File("mixed.e57");
  E57Scan plain = CartesianScan({Eigen::Vector3d(1, 1, 1)}, E57FieldType::kDouble);
  E57Scan rich = CartesianScan({Eigen::Vector3d(2, 2, 2)}, E57FieldType::kDouble);
  for (const char* c : {"colorRed", "colorGreen", "colorBlue"}) {
    rich.fields.push_back(Field(c, E57FieldType::kInteger, {255}, 0, 255));
  }
  rich.fields.push_back(Field("intensity", E57FieldType::kFloat, {0.25}));
  rich.fields.push_back(Field("timeStamp", E57FieldType::kDouble, {1234.5}));
  WriteE57(path, {plain, rich});
  const PointCloud cloud = ReadPointCloud(path);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.colors[0], (Rgb8{128, 128, 128}));
  EXPECT_EQ(cloud.colors[1], (Rgb8{255, 255, 255}));
  EXPECT_EQ(cloud.FindScalar("intensity")->Get(0), 0.0);
  EXPECT_EQ(cloud.FindScalar("intensity")->Get(1), 0.25);
  EXPECT_EQ(cloud.FindScalar("time_stamp")->spec.type, ScalarType::kFloat64);
  EXPECT_EQ(cloud.FindScalar("time_stamp")->Get(1), 1234.5);
  PointReadOptions geometry_only;
  geometry_only.scalar_fields = false;
  EXPECT_TRUE(ReadPointCloud(path, geometry_only).schema.scalars.empty());
}

PointCloud ColouredCloud(size_t n, const Eigen::Vector3d& origin) {
  PointCloud cloud;
  PointSchema schema;
  schema.colors = true;
  schema.scalars.push_back({"intensity", ScalarType::kFloat32});
  schema.position_type = ScalarType::kFloat32;
  cloud.SetSchema(schema);
  cloud.frame.origin = origin;
  cloud.Resize(n);
  const auto p = RandomPoints(n, 50.0, 9);
  for (size_t i = 0; i < n; ++i) {
    cloud.positions[i] = p[i].cast<float>().cast<double>();
    cloud.colors[i] = Rgb8{static_cast<uint8_t>(i), static_cast<uint8_t>(i * 7), 200};
    cloud.scalars[0].f32[i] = static_cast<float>(i % 1000);
  }
  return cloud;
}

TEST(E57Io, PointWriterRoundTripManyPackets) {
  TempDir dir;
  const std::string path = dir.File("cloud.e57");
  const PointCloud cloud = ColouredCloud(200000, Eigen::Vector3d(500000, 4000000, 100));
  PointWriteSpec spec{cloud.schema, cloud.frame, cloud.meta, cloud.size()};
  spec.meta.crs = "EPSG:25832";
  auto writer = OpenPointWriter(path, spec);
  writer->Write(cloud);
  EXPECT_FALSE(testing::FileExists(path));  // atomic: nothing until Close
  writer->Close();
  auto reader = OpenPointReader(path);
  EXPECT_EQ(reader->info().count, cloud.size());
  EXPECT_EQ(reader->info().meta.crs, "EPSG:25832");
  const PointCloud back = ReadPointCloud(path);
  ASSERT_EQ(back.size(), cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    ASSERT_EQ(back.WorldPosition(i), cloud.WorldPosition(i)) << i;  // double: shifted frame
    ASSERT_EQ(back.colors[i], cloud.colors[i]) << i;
    ASSERT_EQ(back.scalars[0].Get(i), cloud.scalars[0].Get(i)) << i;
  }
}

TEST(E57Io, PointWriterSinglePrecisionAndSmallChunks) {
  TempDir dir;
  const std::string path = dir.File("float.e57");
  const PointCloud cloud = ColouredCloud(3000, Eigen::Vector3d::Zero());
  PointWriteSpec spec{cloud.schema, cloud.frame, cloud.meta, kUnknownCount};
  auto writer = OpenE57Writer(path, spec, {});
  PointCloud part;
  part.SetSchema(cloud.schema);
  for (size_t i = 0; i < cloud.size(); ++i) {
    part.Clear();
    part.AppendFrom(cloud, i);
    writer->Write(part);
  }
  writer->Close();
  const PointCloud back = ReadPointCloud(path);
  ASSERT_EQ(back.size(), cloud.size());
  EXPECT_NE(OpenPointReader(path)->info().description.find("cartesian float"), std::string::npos);
  for (size_t i = 0; i < cloud.size(); ++i) ASSERT_EQ(back.positions[i], cloud.positions[i]) << i;
}

// ---- Bad input ----

std::string SmallFile(const TempDir& dir) {
  const std::string path = dir.File("small.e57");
  E57Scan scan = CartesianScan(RandomPoints(400, 1.0, 4), E57FieldType::kDouble);
  scan.fields.push_back(Field("intensity", E57FieldType::kInteger,
                              std::vector<double>(400, 3.0), 0, 8191));
  WriteE57(path, {scan});
  return path;
}

TEST(E57Io, TruncatedFilesAreInputErrors) {
  TempDir dir;
  const std::string good = ReadBytes(SmallFile(dir));
  const std::string path = dir.File("cut.e57");
  for (size_t size = 1; size < good.size(); size += 97) {
    WriteBytes(path, good.substr(0, size));
    std::string error;
    try {
      ReadPointCloud(path);
    } catch (const InputError& e) {
      error = e.what();
    }
    EXPECT_NE(error.find(path), std::string::npos) << size << ": " << error;
  }
}

TEST(E57Io, BitFlipsAreCaughtByTheCrc) {
  TempDir dir;
  const std::string good = ReadBytes(SmallFile(dir));
  const std::string path = dir.File("flip.e57");
  for (size_t at = 0; at < good.size(); at += 61) {
    if (at % e57::kPageSize >= e57::kPageData) continue;  // flips in the CRC itself: also caught
    std::string bad = good;
    bad[at] = static_cast<char>(bad[at] ^ (1 << (at % 8)));
    WriteBytes(path, bad);
    const std::string error = ReadError(path);
    const bool named = error.find(path) != std::string::npos;
    const bool crc = error.find("CRC-32C mismatch") != std::string::npos;
    const bool signature = at < 8;  // the signature is checked before the page
    EXPECT_TRUE(named && (crc || signature)) << at << ": " << error;
  }
}

TEST(E57Io, AbsurdRecordCountIsAnInputError) {
  TempDir dir;
  const std::string path = SmallFile(dir);
  RewriteXml(path, "recordCount=\"400\"", "recordCount=\"9000000000000000000\"");
  const std::string error = ReadError(path);
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("/data3D/0/points"), std::string::npos) << error;
  EXPECT_NE(error.find("recordCount"), std::string::npos) << error;
}

TEST(E57Io, MoreRecordsThanDataIsAnInputError) {
  TempDir dir;
  const std::string path = SmallFile(dir);
  RewriteXml(path, "recordCount=\"400\"", "recordCount=\"401\"");
  const std::string error = ReadError(path);
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("records still to read"), std::string::npos) << error;
}

TEST(E57Io, UnknownCodecIsAnInputError) {
  TempDir dir;
  const std::string path = SmallFile(dir);
  RewriteXml(path, "allowHeterogeneousChildren=\"1\"></codecs>",
             "allowHeterogeneousChildren=\"1\"><vectorChild type=\"Structure\">"
             "<zLibCodec type=\"Structure\"/></vectorChild></codecs>");
  const std::string error = ReadError(path);
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("unsupported E57 codec 'zLibCodec'"), std::string::npos) << error;
  EXPECT_NE(error.find("/data3D/0/points/codecs/0"), std::string::npos) << error;
}

TEST(E57Io, BadXmlAndPrototypesAreInputErrors) {
  TempDir dir;
  const std::string path = SmallFile(dir);
  const std::string good = ReadBytes(path);
  struct Case {
    std::string from, to, expect;
  };
  const std::vector<Case> cases = {
      {"</prototype>", "</prototyp>", "XML parse error"},
      {"<cartesianX type=\"Float\" precision=\"double\"/>",
       "<cartesianX type=\"String\"/>", "type 'String' is not supported"},
      {"<cartesianX type=\"Float\" precision=\"double\"/>", "", "neither cartesianX"},
      {"minimum=\"0\" maximum=\"8191\"", "minimum=\"9\" maximum=\"1\"", "maximum 1 < minimum 9"},
      {"fileOffset=\"", "fileOffset=\"7", "section"},
  };
  for (const Case& c : cases) {
    WriteBytes(path, good);
    RewriteXml(path, c.from, c.to);
    const std::string error = ReadError(path);
    EXPECT_NE(error.find(path), std::string::npos) << c.to << ": " << error;
    EXPECT_NE(error.find(c.expect), std::string::npos) << c.to << ": " << error;
  }
}

TEST(E57Io, BadHeaderFields) {
  TempDir dir;
  const std::string good = ReadBytes(SmallFile(dir));
  const std::string path = dir.File("header.e57");
  std::string bad = good;
  bad[40] = 0;  // page size 1024 -> 0
  bad[41] = 8;  // 2048
  WriteBytes(path, bad);
  EXPECT_NE(ReadError(path).find("page size 2048"), std::string::npos) << ReadError(path);
  WriteBytes(path, "ASTM-E5X" + good.substr(8));
  EXPECT_NE(ReadError(path).find("extension says E57"), std::string::npos) << ReadError(path);
}

TEST(E57Io, WriterRejectsOutOfRangeValues) {
  TempDir dir;
  E57Scan scan = CartesianScan({Eigen::Vector3d(1, 2, 3)}, E57FieldType::kFloat);
  scan.fields.push_back(Field("intensity", E57FieldType::kInteger, {300}, 0, 255));
  EXPECT_THROW(WriteE57(dir.File("bad.e57"), {scan}), std::invalid_argument);
  scan.fields.back().values.push_back(1);
  EXPECT_THROW(WriteE57(dir.File("bad.e57"), {scan}), std::invalid_argument);
  EXPECT_FALSE(testing::FileExists(dir.File("bad.e57")));
}

// Throughput: CANDI_SLOW_TESTS=1, run pinned to one core (taskset -c 0).
TEST(E57Io, ReadSpeed) {
  CANDI_REQUIRE_SLOW_TESTS();
  TempDir dir;
  const std::string path = dir.File("speed.e57");
  const size_t n = 10000000;
  {
    PointCloud cloud = ColouredCloud(n, Eigen::Vector3d::Zero());
    cloud.schema.scalars.clear();
    cloud.scalars.clear();
    WritePointCloud(path, cloud);
  }
  std::vector<double> seconds;
  for (int run = 0; run < 5; ++run) {
    const auto start = std::chrono::steady_clock::now();
    auto reader = OpenPointReader(path);
    PointCloud chunk;
    size_t total = 0;
    while (size_t got = reader->Read(1 << 20, &chunk)) total += got;
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    ASSERT_EQ(total, n);
  }
  std::sort(seconds.begin(), seconds.end());
  std::printf("E57 read: %zu float points with colour, median %.3f s = %.1f M points/s\n", n,
              seconds[2], n / seconds[2] / 1e6);
}

}  // namespace
}  // namespace candi::io

#include "io/ply/ply_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/check.h"
#include "core/rng.h"
#include "io/ply/ply_header.h"
#include "io/point_io.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using testing::FileExists;
using testing::ReadBytes;
using testing::TempDir;
using testing::WriteBytes;

// A cloud at survey scale with every attribute kind, millimetre detail.
PointCloud SurveyCloud(size_t n) {
  PointCloud cloud;
  PointSchema schema;
  schema.colors = schema.alphas = schema.normals = schema.layers = true;
  schema.scalars = {{"intensity", ScalarType::kFloat32}, {"gps_time", ScalarType::kFloat64}};
  cloud.SetSchema(schema);
  cloud.Resize(n);
  Rng rng(7);
  for (size_t i = 0; i < n; ++i) {
    cloud.positions[i] = Eigen::Vector3d(500000.123 + 0.001 * i, 4500000.456 - 0.001 * i, 100.789 + rng.Uniform());
    cloud.colors[i] = {static_cast<uint8_t>(i), static_cast<uint8_t>(3 * i), static_cast<uint8_t>(255 - i % 256)};
    cloud.alphas[i] = static_cast<uint8_t>(i % 256);
    cloud.normals[i] = Eigen::Vector3f(0.6f, 0.0f, -0.8f);
    cloud.layers[i] = static_cast<uint16_t>(i % 4);
    cloud.scalars[0].f32[i] = static_cast<float>(i) * 0.5f;
    cloud.scalars[1].f64[i] = 1.0e9 + i * 1e-6;
  }
  return cloud;
}

void ExpectSameWorld(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.WorldPosition(i), b.WorldPosition(i)) << "point " << i;
  }
}

void ExpectSameAttributes(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(a.colors, b.colors);
  EXPECT_EQ(a.alphas, b.alphas);
  EXPECT_EQ(a.layers, b.layers);
  ASSERT_EQ(a.normals.size(), b.normals.size());
  for (size_t i = 0; i < a.normals.size(); ++i) EXPECT_EQ(a.normals[i], b.normals[i]);
  ASSERT_EQ(a.scalars.size(), b.scalars.size());
  for (size_t k = 0; k < a.scalars.size(); ++k) {
    EXPECT_EQ(a.scalars[k].spec, b.scalars[k].spec);
    EXPECT_EQ(a.scalars[k].f32, b.scalars[k].f32);
    EXPECT_EQ(a.scalars[k].f64, b.scalars[k].f64);
  }
}

class PlyEncodings : public ::testing::TestWithParam<PlyEncoding> {};

TEST_P(PlyEncodings, RoundTripIsExactAtSurveyScale) {
  TempDir dir;
  const PointCloud cloud = SurveyCloud(1000);
  PointWriteOptions options;
  options.ply_encoding = GetParam();
  WritePointCloud(dir.File("a.ply"), cloud, options);
  const PointCloud back = ReadPointCloud(dir.File("a.ply"));
  EXPECT_EQ(back.schema, cloud.schema);
  ExpectSameWorld(cloud, back);
  ExpectSameAttributes(cloud, back);
}

TEST_P(PlyEncodings, ShiftIsRecordedAndExact) {
  TempDir dir;
  PointCloud cloud = SurveyCloud(500);
  LocalFrame frame;
  frame.origin = Eigen::Vector3d(500000, 4500000, 100);
  cloud.Rebase(frame);
  PointWriteOptions options;
  options.ply_encoding = GetParam();
  WritePointCloud(dir.File("s.ply"), cloud, options);
  EXPECT_NE(ReadBytes(dir.File("s.ply")).find("comment candi_shift 500000 4500000 100"), std::string::npos);
  EXPECT_TRUE(FileExists(dir.File("s.ply.shift.json")));
  const PointCloud back = ReadPointCloud(dir.File("s.ply"));
  EXPECT_EQ(back.frame, frame);
  ExpectSameWorld(SurveyCloud(500), back);
  // Local coordinates are small: what a float viewer (MeshLab) sees keeps millimetres.
  EXPECT_LT(back.LocalBounds().max.cwiseAbs().maxCoeff(), 10.0);
}

INSTANTIATE_TEST_SUITE_P(All, PlyEncodings,
                         ::testing::Values(PlyEncoding::kBinaryLittleEndian,
                                           PlyEncoding::kBinaryBigEndian, PlyEncoding::kAscii));

TEST(PlyIo, FloatDataStaysFloat) {
  TempDir dir;
  PointCloud cloud;
  cloud.schema.position_type = ScalarType::kFloat32;
  cloud.Resize(3);
  cloud.positions = {{0.1f, 0.2f, 0.3f}, {1, 2, 3}, {-4, 5, 6}};
  WritePointCloud(dir.File("f.ply"), cloud);
  EXPECT_NE(ReadBytes(dir.File("f.ply")).find("property float x"), std::string::npos);
  const PointCloud back = ReadPointCloud(dir.File("f.ply"));
  EXPECT_EQ(back.schema.position_type, ScalarType::kFloat32);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(back.positions[i], cloud.positions[i]);
}

TEST(PlyIo, StreamingChunksEqualWholeRead) {
  TempDir dir;
  WritePointCloud(dir.File("c.ply"), SurveyCloud(1001));
  const PointCloud whole = ReadPointCloud(dir.File("c.ply"));
  auto reader = OpenPointReader(dir.File("c.ply"));
  PointCloud all, chunk;
  all.SetSchema(reader->info().schema);
  size_t reads = 0;
  while (reader->Read(7, &chunk) > 0) {
    EXPECT_LE(chunk.size(), 7u);
    all.Append(chunk);
    ++reads;
  }
  EXPECT_EQ(reads, 143u);
  ExpectSameWorld(whole, all);
  ExpectSameAttributes(whole, all);
}

TEST(PlyIo, UnknownCountIsPatchedOnClose) {
  TempDir dir;
  const PointCloud cloud = SurveyCloud(10);
  PointWriteSpec spec{cloud.schema, cloud.frame, cloud.meta, kUnknownCount};
  auto writer = OpenPointWriter(dir.File("u.ply"), spec);
  writer->Write(cloud);
  writer->Write(cloud);
  writer->Close();
  const PointCloud back = ReadPointCloud(dir.File("u.ply"));
  EXPECT_EQ(back.size(), 20u);
}

TEST(PlyIo, MeshRoundTripKeepsFaces) {
  TempDir dir;
  TriMesh mesh;
  mesh.vertices.Resize(4);
  mesh.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  mesh.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  for (PlyEncoding e : {PlyEncoding::kBinaryLittleEndian, PlyEncoding::kAscii}) {
    PointWriteOptions options;
    options.ply_encoding = e;
    WritePlyMesh(dir.File("m.ply"), mesh, options);
    const TriMesh back = ReadPlyMesh(dir.File("m.ply"));
    EXPECT_EQ(back.faces, mesh.faces);
    EXPECT_EQ(back.vertices.size(), 4u);
  }
}

TEST(PlyIo, PolygonsAreFannedAndListsSkipped) {
  TempDir dir;
  WriteBytes(dir.File("q.ply"),
             "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
             "property float z\nproperty list uchar int view_indices\nelement face 1\n"
             "property list uchar int vertex_index\nend_header\n"
             "0 0 0 2 5 6\n1 0 0 0\n1 1 0 1 9\n0 1 0 0\n4 0 1 2 3\n");
  const TriMesh mesh = ReadPlyMesh(dir.File("q.ply"));
  EXPECT_EQ(mesh.vertices.size(), 4u);
  ASSERT_EQ(mesh.faces.size(), 2u);
  EXPECT_EQ(mesh.faces[1], (std::array<uint32_t, 3>{0, 2, 3}));
}

TEST(PlyIo, ScalarAndQualityNamesMapBothWays) {
  TempDir dir;
  WriteBytes(dir.File("s.ply"),
             "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
             "property float z\nproperty float scalar_Deviation\nproperty float quality\n"
             "property ushort red\nproperty ushort green\nproperty ushort blue\nend_header\n"
             "1 2 3 0.25 7 65535 0 32896\n");
  const PointCloud cloud = ReadPointCloud(dir.File("s.ply"));
  ASSERT_NE(cloud.FindScalar("Deviation"), nullptr);
  ASSERT_NE(cloud.FindScalar("quality"), nullptr);
  EXPECT_EQ(cloud.FindScalar("Deviation")->Get(0), 0.25);
  EXPECT_EQ(cloud.colors[0], (Rgb8{255, 0, 128}));
  WritePointCloud(dir.File("t.ply"), cloud);
  const std::string text = ReadBytes(dir.File("t.ply"));
  EXPECT_NE(text.find("property float scalar_Deviation"), std::string::npos);
  EXPECT_NE(text.find("property float quality"), std::string::npos);
}

// --- real data -------------------------------------------------------------------------------

TEST(PlyIo, ReadsLauranaMeshWithRgba) {
  CANDI_REQUIRE_SHARED_DATA(path, "ply/Laurana50k.ply");
  const TriMesh mesh = ReadPlyMesh(path);
  EXPECT_EQ(mesh.vertices.size(), 27861u);
  EXPECT_EQ(mesh.faces.size(), 49954u);
  EXPECT_TRUE(mesh.vertices.schema.colors);
  EXPECT_TRUE(mesh.vertices.schema.alphas);
  const Box3d box = mesh.vertices.WorldBounds();
  EXPECT_FALSE(box.IsEmpty());
  EXPECT_GT(box.Extent().norm(), 1e-3);
  EXPECT_LT(box.Extent().norm(), 1e4);
}

TEST(PlyIo, ReadsBunnyWithFaceFlags) {
  CANDI_REQUIRE_SHARED_DATA(path, "ply/bunny10k.ply");
  const TriMesh mesh = ReadPlyMesh(path);
  EXPECT_EQ(mesh.vertices.size(), 6164u);
  EXPECT_EQ(mesh.faces.size(), 9999u);
  EXPECT_NE(mesh.vertices.FindScalar("flags"), nullptr);
}

TEST(PlyIo, ReadsOpenMvsDenseCloudSkippingListProperties) {
  CANDI_REQUIRE_SHARED_DATA(path, "dense/sceaux_openmvs_dense.ply");
  auto reader = OpenPointReader(path);
  EXPECT_EQ(reader->info().count, 402504u);
  const PointCloud cloud = ReadPointCloud(path);
  ASSERT_EQ(cloud.size(), 402504u);
  EXPECT_TRUE(cloud.schema.colors);
  EXPECT_TRUE(cloud.schema.normals);
  EXPECT_TRUE(cloud.schema.scalars.empty());
  const Box3d box = cloud.WorldBounds();
  EXPECT_GT(box.Extent().minCoeff(), 0.1);
  EXPECT_LT(box.Extent().maxCoeff(), 1e4);
  // Normals are unit vectors: decoding through the list properties kept the record alignment.
  double worst = 0;
  for (const auto& n : cloud.normals) worst = std::max(worst, std::abs(n.norm() - 1.0));
  EXPECT_LT(worst, 1e-3);
}

// --- bad input -------------------------------------------------------------------------------

std::string MinimalBinaryPly(uint64_t claimed, int present) {
  std::string text = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(claimed) +
                     "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  for (int i = 0; i < present * 3; ++i) {
    const float v = static_cast<float>(i);
    text.append(reinterpret_cast<const char*>(&v), 4);
  }
  return text;
}

void ExpectInputError(const std::string& path, const std::string& fragment) {
  try {
    ReadPointCloud(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

TEST(PlyBadInput, TruncatedBody) {
  TempDir dir;
  std::string bytes = MinimalBinaryPly(10, 10);
  bytes.resize(bytes.size() - 5);
  WriteBytes(dir.File("t.ply"), bytes);
  ExpectInputError(dir.File("t.ply"), "byte");
}

TEST(PlyBadInput, HeaderClaimsMoreThanTheFileHolds) {
  TempDir dir;
  WriteBytes(dir.File("h.ply"), MinimalBinaryPly(1000000000000ull, 2));
  ExpectInputError(dir.File("h.ply"), "header promises 1000000000000 vertex");
}

TEST(PlyBadInput, UnknownPropertyType) {
  TempDir dir;
  WriteBytes(dir.File("u.ply"), "ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\nend_header\n1\n");
  ExpectInputError(dir.File("u.ply"), "line 4: unknown property type 'float128'");
}

TEST(PlyBadInput, NanCoordinate) {
  TempDir dir;
  WriteBytes(dir.File("n.ply"), "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                                "property float y\nproperty float z\nend_header\n1 2 3\nnan 0 0\n");
  ExpectInputError(dir.File("n.ply"), "vertex 1: coordinate is NaN");
  std::string bytes = MinimalBinaryPly(2, 2);
  const float inf = std::numeric_limits<float>::infinity();
  bytes.replace(bytes.size() - 4, 4, reinterpret_cast<const char*>(&inf), 4);
  WriteBytes(dir.File("i.ply"), bytes);
  ExpectInputError(dir.File("i.ply"), "vertex 1");
  // Vertices are decoded and checked in parallel blocks: of two bad vertices in different
  // blocks, the first is named, whatever the threads.
  std::string many = MinimalBinaryPly(50000, 50000);
  const size_t header = many.size() - 50000 * 12;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  many.replace(header + 41000 * 12 + 4, 4, reinterpret_cast<const char*>(&nan), 4);
  many.replace(header + 9000 * 12 + 8, 4, reinterpret_cast<const char*>(&inf), 4);
  WriteBytes(dir.File("many.ply"), many);
  ExpectInputError(dir.File("many.ply"), "vertex 9000: coordinate is NaN or infinite");
}

TEST(PlyBadInput, WrongMagicAndMissingEndHeader) {
  TempDir dir;
  WriteBytes(dir.File("m.ply"), "plx\nformat ascii 1.0\n");
  EXPECT_THROW(ReadPointCloud(dir.File("m.ply")), InputError);
  WriteBytes(dir.File("e.ply"), "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n");
  ExpectInputError(dir.File("e.ply"), "no end_header");
}

TEST(PlyBadInput, AsciiValueErrorsNameTheLine) {
  TempDir dir;
  WriteBytes(dir.File("a.ply"), "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                                "property float y\nproperty float z\nproperty uchar red\n"
                                "property uchar green\nproperty uchar blue\nend_header\n"
                                "1 2 3 4 5 6\n1 2 3 4 300 6\n");
  ExpectInputError(dir.File("a.ply"), "line 12: value 300 of green is not a uchar");
  WriteBytes(dir.File("b.ply"), "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                                "property float y\nproperty float z\nend_header\n1 2 abc\n");
  ExpectInputError(dir.File("b.ply"), "line 8: 'abc' is not a number");
  WriteBytes(dir.File("c.ply"), "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                                "property float y\nproperty float z\nend_header\n1.000000 2.000000 3.000000\n");
  ExpectInputError(dir.File("c.ply"), "file ends after 1 of 2 vertices");
}

TEST(PlyBadInput, FaceIndexOutOfRange) {
  TempDir dir;
  WriteBytes(dir.File("f.ply"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                                "property float y\nproperty float z\nelement face 1\n"
                                "property list uchar int vertex_indices\nend_header\n"
                                "0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n");
  EXPECT_THROW(ReadPlyMesh(dir.File("f.ply")), InputError);
}

// Float index lists are legal PLY; 1e30, NaN or 1.5 used to be cast to int64 (undefined
// behaviour, issue 9's fuzzing). They are now out-of-range indices, ascii and binary alike.
TEST(PlyBadInput, NonIntegralFloatFaceIndicesAreOutOfRange) {
  TempDir dir;
  const std::string header =
      "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar float vertex_indices\nend_header\n";
  for (const char* bad : {"1e30", "nan", "1.5", "-3e19"}) {
    WriteBytes(dir.File("f.ply"), "ply\nformat ascii 1.0\n" + header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 " +
                                      bad + "\n");
    try {
      ReadPlyMesh(dir.File("f.ply"));
      ADD_FAILURE() << "accepted face index " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("vertex index -1 outside [0, 3)"), std::string::npos)
          << e.what();
    }
  }
  std::string binary = "ply\nformat binary_little_endian 1.0\n" + header;
  const float body[] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  binary.append(reinterpret_cast<const char*>(body), sizeof(body));
  const float face[] = {0, 1, std::numeric_limits<float>::infinity()};
  binary.push_back(3);
  binary.append(reinterpret_cast<const char*>(face), sizeof(face));
  WriteBytes(dir.File("b.ply"), binary);
  EXPECT_THROW(ReadPlyMesh(dir.File("b.ply")), InputError);
  std::string good = binary.substr(0, binary.size() - 4);
  const float two = 2;
  good.append(reinterpret_cast<const char*>(&two), 4);
  WriteBytes(dir.File("g.ply"), good);
  EXPECT_EQ(ReadPlyMesh(dir.File("g.ply")).faces.size(), 1u);
}

TEST(PlyWriterSafety, DestroyedWriterLeavesTheEarlierFileIntact) {
  TempDir dir;
  const PointCloud cloud = SurveyCloud(10);
  WritePointCloud(dir.File("keep.ply"), cloud);
  const std::string before = ReadBytes(dir.File("keep.ply"));
  {
    PointWriteSpec spec{cloud.schema, cloud.frame, cloud.meta, 5};
    auto writer = OpenPointWriter(dir.File("keep.ply"), spec);
    PointCloud half = cloud;
    half.Resize(5);
    half.positions[0].x() = 1.0;
    writer->Write(half);
    // No Close(): an interrupted write.
  }
  EXPECT_EQ(ReadBytes(dir.File("keep.ply")), before);
  EXPECT_THROW(WritePointCloud(dir.File("no/such/dir/x.ply"), cloud), InputError);
  EXPECT_FALSE(FileExists(dir.File("no/such/dir/x.ply")));
}

}  // namespace
}  // namespace candi::io

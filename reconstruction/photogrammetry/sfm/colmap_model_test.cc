#include "reconstruction/photogrammetry/sfm/colmap_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>

#include "core/check.h"
#include "tests/util/test_util.h"

namespace candi::photogrammetry {
namespace {

using candi::testing::ReadBytes;
using candi::testing::TempDir;
using candi::testing::WriteBytes;

// A small model built in code: two cameras, three images, points seen by two or three images,
// values that need all 17 digits.
ColmapModel MakeModel() {
  ColmapModel m;
  m.cameras[1] = {1, "SIMPLE_RADIAL", 640, 480, {500.1234567890123, 320.5, 240.25, -0.0123456789}};
  m.cameras[7] = {7, "OPENCV", 800, 600, {600, 601, 400, 300, 0.01, -0.002, 1e-4, -2e-4}};
  for (uint32_t i = 1; i <= 3; ++i) {
    ColmapImage& im = m.images[i * 10];
    im.image_id = i * 10;
    im.camera_id = i == 3 ? 7 : 1;
    im.name = "img_" + std::to_string(i) + ".jpg";
    im.cam_from_world_rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * i, Eigen::Vector3d(0.3, 1, 0.2).normalized()));
    im.cam_from_world_translation = Eigen::Vector3d(0.1 * i, -0.2, 1.0 / 3.0);
  }
  for (uint64_t p = 0; p < 5; ++p) {
    ColmapPoint3d& pt = m.points3d[100 + p];
    pt.point3d_id = 100 + p;
    pt.xyz = Eigen::Vector3d(p * 0.1 + 1e-9, std::sqrt(2.0) * p, 5.0 + M_PI * p);
    pt.rgb = {static_cast<uint8_t>(p * 50), 7, 255};
    pt.error = 0.1 * p + 1.0 / 7.0;
    for (uint32_t i = 1; i <= (p % 2 == 0 ? 3u : 2u); ++i) {
      ColmapImage& im = m.images[i * 10];
      pt.track.push_back({i * 10, static_cast<uint32_t>(im.points2d.size())});
      im.points2d.emplace_back(10.5 + p, 20.25 * i);
      im.point3d_ids.push_back(100 + p);
    }
  }
  m.images[20].points2d.emplace_back(1.0 / 3.0, 2.0 / 3.0);  // an untriangulated keypoint
  m.images[20].point3d_ids.push_back(kInvalidPoint3dId);
  return m;
}

void ExpectSameModel(const ColmapModel& a, const ColmapModel& b) {
  ASSERT_EQ(a.cameras.size(), b.cameras.size());
  for (const auto& [id, c] : a.cameras) {
    const ColmapCamera& d = b.cameras.at(id);
    EXPECT_EQ(c.camera_id, d.camera_id);
    EXPECT_EQ(c.model, d.model);
    EXPECT_EQ(c.width, d.width);
    EXPECT_EQ(c.height, d.height);
    EXPECT_EQ(c.params, d.params);
  }
  ASSERT_EQ(a.images.size(), b.images.size());
  for (const auto& [id, im] : a.images) {
    const ColmapImage& jm = b.images.at(id);
    EXPECT_EQ(im.image_id, jm.image_id);
    EXPECT_EQ(im.cam_from_world_rotation.coeffs(), jm.cam_from_world_rotation.coeffs());
    EXPECT_EQ(im.cam_from_world_translation, jm.cam_from_world_translation);
    EXPECT_EQ(im.camera_id, jm.camera_id);
    EXPECT_EQ(im.name, jm.name);
    EXPECT_EQ(im.points2d, jm.points2d);
    EXPECT_EQ(im.point3d_ids, jm.point3d_ids);
  }
  ASSERT_EQ(a.points3d.size(), b.points3d.size());
  for (const auto& [id, p] : a.points3d) {
    const ColmapPoint3d& q = b.points3d.at(id);
    EXPECT_EQ(p.xyz, q.xyz);
    EXPECT_EQ(p.rgb, q.rgb);
    EXPECT_EQ(p.error, q.error);
    ASSERT_EQ(p.track.size(), q.track.size());
    for (size_t t = 0; t < p.track.size(); ++t) {
      EXPECT_EQ(p.track[t].image_id, q.track[t].image_id);
      EXPECT_EQ(p.track[t].point2d_idx, q.track[t].point2d_idx);
    }
  }
}

// Runs `f`, expects an InputError whose message contains every one of `parts`.
template <typename F>
void ExpectInputError(F f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    for (const std::string& part : parts) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what() << " lacks " << part;
    }
  }
}

TEST(ColmapModel, CameraModelTable) {
  EXPECT_EQ(CameraModelId("SIMPLE_PINHOLE"), 0);
  EXPECT_EQ(CameraModelId("SIMPLE_RADIAL"), 2);
  EXPECT_EQ(CameraModelId("THIN_PRISM_FISHEYE"), 10);
  EXPECT_EQ(CameraModelId("NOPE"), -1);
  EXPECT_EQ(CameraModelName(6), "FULL_OPENCV");
  EXPECT_EQ(CameraModelName(11), "");
  EXPECT_EQ(CameraModelNumParams("OPENCV"), 8);
  EXPECT_EQ(CameraModelNumParams("FOV"), 5);
  EXPECT_EQ(CameraModelNumParams("RADIAL_FISHEYE"), 5);
}

TEST(ColmapModel, BinaryTextRoundTripsAreExact) {
  TempDir dir;
  const ColmapModel model = MakeModel();
  WriteColmapModelBinary(model, dir.File("bin"));
  const ColmapModel from_bin = ReadColmapModel(dir.File("bin"));
  ExpectSameModel(model, from_bin);
  WriteColmapModelText(from_bin, dir.File("txt"));
  const ColmapModel from_txt = ReadColmapModel(dir.File("txt"));
  ExpectSameModel(model, from_txt);
  WriteColmapModelBinary(from_txt, dir.File("bin2"));
  for (const char* f : {"cameras.bin", "images.bin", "points3D.bin"}) {
    EXPECT_EQ(ReadBytes(dir.File(std::string("bin/") + f)), ReadBytes(dir.File(std::string("bin2/") + f)))
        << f;
  }
  // COLMAP's text layout: header comments, then one line per camera.
  const std::string cameras = ReadBytes(dir.File("txt/cameras.txt"));
  EXPECT_NE(cameras.find("# Number of cameras: 2\n1 SIMPLE_RADIAL 640 480 500.12345678901232 320.5 "
                         "240.25 -0.0123456789"),
            std::string::npos)
      << cameras;
  EXPECT_NE(ReadBytes(dir.File("txt/images.txt")).find(" -1\n"), std::string::npos);
}

TEST(ColmapModel, EmptyModelRoundTrips) {
  TempDir dir;
  WriteColmapModelBinary(ColmapModel{}, dir.path());
  EXPECT_EQ(ReadBytes(dir.File("points3D.bin")), std::string(8, '\0'));
  const ColmapModel m = ReadColmapModel(dir.path());
  EXPECT_TRUE(m.cameras.empty() && m.images.empty() && m.points3d.empty());
  EXPECT_EQ(MeanReprojectionError(m), 0.0);
}

TEST(ColmapModel, MissingModelNamesTheFolder) {
  TempDir dir;
  ExpectInputError([&] { ReadColmapModel(dir.path()); }, {dir.path(), "cameras.bin"});
}

TEST(ColmapModel, TruncatedBinaryNamesFileAndByte) {
  TempDir dir;
  WriteColmapModelBinary(MakeModel(), dir.path());
  const std::string images = ReadBytes(dir.File("images.bin"));
  WriteBytes(dir.File("images.bin"), images.substr(0, images.size() - 5));
  ExpectInputError([&] { ReadColmapModel(dir.path()); }, {"images.bin", "byte "});
  // Every prefix of points3D.bin fails cleanly (never a crash or a silent partial model).
  WriteBytes(dir.File("images.bin"), images);
  const std::string points = ReadBytes(dir.File("points3D.bin"));
  for (size_t n = 0; n < points.size(); n += 7) {
    WriteBytes(dir.File("points3D.bin"), points.substr(0, n));
    ExpectInputError([&] { ReadColmapModel(dir.path()); }, {"points3D.bin", "byte "});
  }
}

TEST(ColmapModel, HugeCountIsRefusedWithoutAllocating) {
  TempDir dir;
  WriteColmapModelBinary(MakeModel(), dir.path());
  std::string points = ReadBytes(dir.File("points3D.bin"));
  const uint64_t huge = 1000000000000ull;
  std::memcpy(&points[0], &huge, 8);
  WriteBytes(dir.File("points3D.bin"), points);
  ExpectInputError([&] { ReadColmapModel(dir.path()); },
                   {"points3D.bin", "byte 0", "1000000000000", "does not fit"});
  // A huge track length inside a record: the byte offset of the field.
  std::memcpy(&points[0], "\x05\0\0\0\0\0\0\0", 8);
  const size_t track_length_at = 8 + 8 + 24 + 3 + 8;
  std::memcpy(&points[track_length_at], &huge, 8);
  WriteBytes(dir.File("points3D.bin"), points);
  ExpectInputError([&] { ReadColmapModel(dir.path()); },
                   {"byte " + std::to_string(track_length_at), "track length"});
}

TEST(ColmapModel, UnknownCameraModelIdAndNaN) {
  TempDir dir;
  WriteColmapModelBinary(MakeModel(), dir.path());
  std::string cameras = ReadBytes(dir.File("cameras.bin"));
  const std::string good = cameras;
  const int32_t bad_model = 42;
  std::memcpy(&cameras[8 + 4], &bad_model, 4);
  WriteBytes(dir.File("cameras.bin"), cameras);
  ExpectInputError([&] { ReadColmapModel(dir.path()); }, {"cameras.bin", "byte 12", "model id 42"});
  cameras = good;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::memcpy(&cameras[8 + 4 + 4 + 16], &nan, 8);
  WriteBytes(dir.File("cameras.bin"), cameras);
  ExpectInputError([&] { ReadColmapModel(dir.path()); }, {"cameras.bin", "byte 32", "non-finite"});
  WriteBytes(dir.File("cameras.bin"), good + "x");
  ExpectInputError([&] { ReadColmapModel(dir.path()); }, {"cameras.bin", "unexpected bytes"});
}

TEST(ColmapModel, BadTextNamesFileAndLine) {
  TempDir dir;
  WriteColmapModelText(MakeModel(), dir.path());
  const std::string cameras = ReadBytes(dir.File("cameras.txt"));
  WriteBytes(dir.File("cameras.txt"), "# c\n1 PINHOLE 640 480 1 2 3\n");
  ExpectInputError([&] { ReadColmapModel(dir.path()); },
                   {"cameras.txt", "line 2", "PINHOLE takes 4 parameters, the line has 3"});
  WriteBytes(dir.File("cameras.txt"), "1 FISH 640 480 1 2 3\n");
  ExpectInputError([&] { ReadColmapModel(dir.path()); }, {"line 1", "unknown camera model 'FISH'"});
  WriteBytes(dir.File("cameras.txt"), "1 PINHOLE 640 480 1 nan 3 4\n");
  ExpectInputError([&] { ReadColmapModel(dir.path()); }, {"line 1", "non-finite"});
  WriteBytes(dir.File("cameras.txt"), cameras);
  WriteBytes(dir.File("points3D.txt"), "# p\n\n100 1 2 3 255 0 0 0.5 10 0 20\n");
  ExpectInputError([&] { ReadColmapModel(dir.path()); }, {"points3D.txt", "line 3", "pairs"});
  WriteBytes(dir.File("points3D.txt"), "100 1 2 x 255 0 0 0.5 10 0\n");
  ExpectInputError([&] { ReadColmapModel(dir.path()); }, {"points3D.txt", "line 1", "'x'"});
  WriteBytes(dir.File("points3D.txt"), "100 1 2 3 255 0 0 0.5 10 999\n");
  ExpectInputError([&] { ReadColmapModel(dir.path()); }, {"points3D.txt", "(10, 999)"});
  WriteBytes(dir.File("images.txt"), "10 1 0 0 0 0 0 0 1 a.jpg\n");
  ExpectInputError([&] { ReadColmapModel(dir.path()); }, {"images.txt", "POINTS2D line"});
}

TEST(ColmapModel, ProjectionOfPinholeAndRadialModels) {
  ColmapImage image;
  image.cam_from_world_translation = Eigen::Vector3d(0, 0, 2);
  const Eigen::Vector3d X(0.2, -0.1, 0);  // camera frame (0.2, -0.1, 2): u = 0.1, v = -0.05
  ColmapCamera pinhole{1, "PINHOLE", 100, 100, {100, 200, 50, 40}};
  EXPECT_TRUE(ProjectToImage(pinhole, image, X).isApprox(Eigen::Vector2d(60, 30)));
  ColmapCamera radial{1, "SIMPLE_RADIAL", 100, 100, {100, 50, 40, 0.5}};
  const double r2 = 0.01 + 0.0025, s = 1 + 0.5 * r2;
  EXPECT_TRUE(ProjectToImage(radial, image, X).isApprox(Eigen::Vector2d(50 + 10 * s, 40 - 5 * s)));
  // OPENCV with zero distortion equals PINHOLE; FULL_OPENCV with k1 equals RADIAL's first term.
  ColmapCamera opencv{1, "OPENCV", 100, 100, {100, 200, 50, 40, 0, 0, 0, 0}};
  EXPECT_TRUE(ProjectToImage(opencv, image, X).isApprox(Eigen::Vector2d(60, 30)));
  ColmapCamera full{1, "FULL_OPENCV", 100, 100, {100, 100, 50, 40, 0.5, 0, 0, 0, 0, 0, 0, 0}};
  EXPECT_TRUE(ProjectToImage(full, image, X).isApprox(ProjectToImage(radial, image, X)));
  EXPECT_TRUE(std::isnan(ProjectToImage(pinhole, image, Eigen::Vector3d(0, 0, -3)).x()));
  ColmapCamera fov{1, "FOV", 100, 100, {1, 1, 1, 1, 1}};
  EXPECT_THROW(ProjectToImage(fov, image, X), std::invalid_argument);
}

TEST(ColmapArray, RoundTripAndLayout) {
  TempDir dir;
  ColmapArray a;
  a.width = 3;
  a.height = 2;
  a.channels = 3;
  a.data.resize(18);
  for (size_t i = 0; i < a.data.size(); ++i) a.data[i] = 0.5f * i - 1.0f / 3.0f;
  WriteColmapArray(a, dir.File("n.bin"));
  const std::string bytes = ReadBytes(dir.File("n.bin"));
  EXPECT_EQ(bytes.substr(0, 6), "3&2&3&");
  EXPECT_EQ(bytes.size(), 6 + 18 * 4u);
  const ColmapArray b = ReadColmapArray(dir.File("n.bin"));
  EXPECT_EQ(b.width, 3);
  EXPECT_EQ(b.height, 2);
  EXPECT_EQ(b.channels, 3);
  EXPECT_EQ(b.data, a.data);
  EXPECT_EQ(b.at(2, 1, 1), a.data[(1 * 2 + 1) * 3 + 2]);  // channel-planar
}

TEST(ColmapArray, BadFilesNameThePosition) {
  TempDir dir;
  const std::string path = dir.File("d.bin");
  WriteBytes(path, "garbage");
  ExpectInputError([&] { ReadColmapArray(path); }, {path, "byte 0", "bad header"});
  WriteBytes(path, "4&x&1&");
  ExpectInputError([&] { ReadColmapArray(path); }, {"byte 2", "'x'"});
  WriteBytes(path, "0&2&1&");
  ExpectInputError([&] { ReadColmapArray(path); }, {"byte 0"});
  WriteBytes(path, "2&2&1&" + std::string(12, '\0'));  // 3 of 4 floats
  ExpectInputError([&] { ReadColmapArray(path); }, {"byte 6", "needs 4 floats but 12 bytes follow"});
  WriteBytes(path, "1000000&1000000&1000&" + std::string(16, '\0'));  // 10^15 floats claimed
  ExpectInputError([&] { ReadColmapArray(path); }, {"needs 1000000000000000 floats"});
  // 2^30 x 2^30 x 16 = 2^64 floats wraps to 0 in 64 bits and matched an empty body once.
  WriteBytes(path, "1073741824&1073741824&16&");
  ExpectInputError([&] { ReadColmapArray(path); }, {"byte 25", "needs more than 2^64 floats"});
  const float values[2] = {1.0f, std::numeric_limits<float>::quiet_NaN()};
  WriteBytes(path, "2&1&1&" + std::string(reinterpret_cast<const char*>(values), 8));
  ExpectInputError([&] { ReadColmapArray(path); }, {"byte 10", "non-finite"});
  ExpectInputError([&] { ReadColmapArray(dir.File("absent.bin")); }, {"absent.bin"});
}

// The real COLMAP 3.8 model of the Sceaux photos (../shared/data/README.md).
TEST(ColmapModel, ReadsSceauxSparseModel) {
  CANDI_REQUIRE_SHARED_DATA(dir, "colmap/sceaux_1600_sparse");
  const ColmapModel m = ReadColmapModel(dir);
  ASSERT_EQ(m.cameras.size(), 1u);
  EXPECT_EQ(m.cameras.begin()->second.model, "SIMPLE_RADIAL");
  EXPECT_EQ(m.images.size(), 11u);
  EXPECT_EQ(m.points3d.size(), 8450u);
  size_t observations = 0;
  for (const auto& [id, point] : m.points3d) {
    EXPECT_GE(point.track.size(), 2u);
    for (const ColmapTrackElement& e : point.track) {
      const ColmapImage& image = m.images.at(e.image_id);
      ASSERT_LT(e.point2d_idx, image.point3d_ids.size());
      EXPECT_EQ(image.point3d_ids[e.point2d_idx], id);
      ++observations;
    }
  }
  size_t back = 0;  // the reverse direction: every triangulated keypoint is in its point's track
  for (const auto& [id, image] : m.images) {
    for (const uint64_t p : image.point3d_ids) back += p != kInvalidPoint3dId;
    EXPECT_NEAR(image.cam_from_world_rotation.norm(), 1.0, 1e-9);
  }
  EXPECT_EQ(back, observations);
  const double mean = MeanReprojectionError(m);
  EXPECT_GT(mean, 0.1);
  EXPECT_LT(mean, 2.0);
}

// Each point reprojects into its observations within its stored (mean) error: the mean over the
// track of the reprojection distances equals the stored error up to COLMAP's last bundle update.
TEST(ColmapModel, SceauxPointsReprojectWithinTheirError) {
  CANDI_REQUIRE_SHARED_DATA(dir, "colmap/sceaux_1600_sparse");
  const ColmapModel m = ReadColmapModel(dir);
  double worst_excess = 0, sum = 0;
  size_t n = 0;
  for (const auto& [id, point] : m.points3d) {
    double point_sum = 0;
    for (const ColmapTrackElement& e : point.track) {
      const ColmapImage& image = m.images.at(e.image_id);
      const Eigen::Vector2d projected = ProjectToImage(m.cameras.at(image.camera_id), image, point.xyz);
      const double d = (projected - image.points2d[e.point2d_idx]).norm();
      point_sum += d;
      sum += d;
      ++n;
    }
    worst_excess = std::max(worst_excess, point_sum / point.track.size() - point.error);
  }
  EXPECT_LT(worst_excess, 0.05) << "pixels beyond a point's stored mean error";
  EXPECT_LT(sum / n, 2.0);
}

}  // namespace
}  // namespace candi::photogrammetry

// The LAS writer encodes a chunk's records by blocks on the pool's threads: the same bytes on
// one and two threads for LAS, LAZ and COPC, the header's bounds and return counts added up over
// the blocks, and the first point out of int32's range named whichever block holds it.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "core/binary_file.h"
#include "io/las/las_header.h"
#include "io/las/las_io.h"
#include "io/point_io.h"
#include "tests/util/input_error.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using ::candi::testing::FileExists;
using ::candi::testing::InputErrorMessage;
using ::candi::testing::ReadBytes;
using ::candi::testing::TempDir;

// A cloud of `n` points with returns (1-5 of 5), colour and GPS time, in many record blocks.
PointCloud MakeReturnsCloud(size_t n) {
  PointCloud cloud;
  PointSchema schema;
  schema.colors = true;
  schema.scalars = {{las_field::kReturnNumber, ScalarType::kFloat32},
                    {las_field::kNumberOfReturns, ScalarType::kFloat32},
                    {las_field::kGpsTime, ScalarType::kFloat64}};
  cloud.SetSchema(schema);
  cloud.frame.origin = Eigen::Vector3d(500000.0, 4500000.0, 0.0);
  cloud.Resize(n);
  for (size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i);
    cloud.positions[i] = Eigen::Vector3d(40.0 * std::sin(0.001 * t), 0.01 * t, std::cos(0.37 * t));
    cloud.colors[i] = Rgb8{static_cast<uint8_t>(i % 256), static_cast<uint8_t>(i / 256 % 256), 7};
    cloud.scalars[0].f32[i] = static_cast<float>(1 + (i * 7) % 5);
    cloud.scalars[1].f32[i] = 5.0f;
    cloud.scalars[2].f64[i] = 3.0e5 + 1e-4 * t;
  }
  return cloud;
}

TEST(LasWrite, RecordsEncodedByBlocksInParallelAreTheSameBytesOnOneAndTwoThreads) {
  // 300,001 points in chunks of 100,000: rounds of 16 blocks of 4,096 records and a last block
  // of one, through LAS, LAZ and COPC; the header's bounds and return counts add up the blocks.
  TempDir dir;
  const PointCloud cloud = MakeReturnsCloud(300001);
  PointWriteOptions options;
  options.las_scale = Eigen::Vector3d::Constant(0.001);
  for (const char* name : {"p.las", "p.laz", "p.copc.laz"}) {
    std::string bytes[2];
    for (int threads : {1, 2}) {
      const std::string path = dir.File(std::to_string(threads) + name);
      tbb::task_arena arena(threads);
      arena.execute([&] {
        auto writer = OpenPointWriter(path, {cloud.schema, cloud.frame, cloud.meta, cloud.size()},
                                      options);
        for (size_t first = 0; first < cloud.size(); first += 100000) {
          PointCloud chunk;
          chunk.SetSchema(cloud.schema);
          chunk.frame = cloud.frame;
          for (size_t i = first; i < std::min(cloud.size(), first + 100000); ++i) {
            chunk.AppendFrom(cloud, i);
          }
          writer->Write(chunk);
        }
        writer->Close();
      });
      bytes[threads - 1] = ReadBytes(path);
    }
    EXPECT_EQ(bytes[0], bytes[1]) << name;
    BinaryFile file(dir.File(std::string("2") + name));
    const LasHeader header = ReadLasHeader(&file);
    const bool wide = header.version_minor >= 4;
    EXPECT_EQ(wide ? header.count : header.legacy_count, cloud.size()) << name;
    for (int r = 1; r <= 5; ++r) {
      const uint64_t count = wide ? header.by_return[r - 1] : header.legacy_by_return[r - 1];
      EXPECT_EQ(count, r == 1 ? 60001u : 60000u) << name << " " << r;
    }
    const Box3d box = cloud.WorldBounds();
    EXPECT_NEAR((header.bounds.min - box.min).cwiseAbs().maxCoeff(), 0.0, 0.0005) << name;
    EXPECT_NEAR((header.bounds.max - box.max).cwiseAbs().maxCoeff(), 0.0, 0.0005) << name;
  }
}

TEST(LasWrite, TheFirstPointOutsideInt32IsNamedWhicheverBlockHasIt) {
  // Two points out of range, in different blocks of one chunk: the earlier is named, on two
  // threads as on one, for LAS and COPC; nothing is left under the name.
  TempDir dir;
  PointCloud cloud = MakeReturnsCloud(100000);
  cloud.frame.origin = Eigen::Vector3d::Zero();  // the points within 40 m of the offset
  cloud.positions[70000] = Eigen::Vector3d(1.0e7, 0.0, 0.0);
  cloud.positions[5000] = Eigen::Vector3d(0.0, -1.0e7, 0.0);
  PointWriteOptions options;
  options.las_scale = Eigen::Vector3d::Constant(0.001);
  options.las_offset = Eigen::Vector3d::Zero();
  for (const char* name : {"far.las", "far.copc.laz"}) {
    for (int threads : {1, 2}) {
      const std::string path = dir.File(name);
      tbb::task_arena arena(threads);
      std::string error;
      arena.execute([&] {
        error = InputErrorMessage([&] { WritePointCloud(path, cloud, options); });
      });
      EXPECT_NE(error.find("point 5000:"), std::string::npos) << error;
      EXPECT_FALSE(FileExists(path));
    }
  }
}

}  // namespace
}  // namespace candi::io

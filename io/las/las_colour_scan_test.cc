#include "io/las/las_colour_scan_internal.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstring>
#include <fstream>
#include <string>

#include "core/atomic_file.h"
#include "io/point_io.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

// The colour scan runs once per file as it is: a file rewritten in place with the same size and
// modification time keeps its first answer (the proof that the second open did not scan), and
// a new modification time scans again.
TEST(LasColourScan, OncePerFileAsItIs) {
  candi::testing::TempDir dir;
  const std::string path = dir.File("colours.las");
  PointCloud cloud;
  cloud.schema.colors = true;
  cloud.SetSchema(cloud.schema);
  cloud.Resize(2000);
  for (size_t i = 0; i < cloud.size(); ++i) {
    cloud.positions[i] = Eigen::Vector3d(0.01 * i, 0.5, 1.0);
    cloud.colors[i] = {200, static_cast<uint8_t>(i), 40};
  }
  WritePointCloud(path, cloud);
  const bool wide = OpenPointReader(path)->info().meta.las.color_16bit;
  EXPECT_TRUE(wide) << "candi writes 8-bit colours scaled to 16 bits";
  struct stat before {};
  ASSERT_EQ(stat(path.c_str(), &before), 0);
  // Every colour's high bytes cleared (8-bit colours as many files store them), in place.
  std::string bytes = ReadFileToString(path);
  auto reader = OpenPointReader(path);
  const PointRecordLayout layout = *reader->record_layout();
  reader.reset();
  for (uint64_t i = 0; i < layout.count; ++i) {
    for (int c = 0; c < 3; ++c) bytes[layout.first_byte + i * layout.stride + layout.rgb[c] + 1] = 0;
  }
  {
    std::ofstream out(path, std::ios::binary | std::ios::in | std::ios::out);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  const timespec same[2] = {before.st_atim, before.st_mtim};
  ASSERT_EQ(utimensat(AT_FDCWD, path.c_str(), same, 0), 0);
  EXPECT_TRUE(OpenPointReader(path)->info().meta.las.color_16bit) << "scanned again";
  timespec later[2] = {before.st_atim, before.st_mtim};
  later[1].tv_sec += 10;
  ASSERT_EQ(utimensat(AT_FDCWD, path.c_str(), later, 0), 0);
  EXPECT_FALSE(OpenPointReader(path)->info().meta.las.color_16bit) << "a changed file keeps the old answer";
  // Without a file (a name that is not one), every call scans.
  int scans = 0;
  for (int i = 0; i < 2; ++i) CachedWideColours(dir.File("none.las"), [&] { return ++scans > 0; });
  EXPECT_EQ(scans, 2);
}

}  // namespace
}  // namespace candi::io

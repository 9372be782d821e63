// Test helper (header-only, for io's LAS/LAZ/COPC tests): LAS records that look like a scan, made
// from a seeded RNG, and a cloud carrying every LAS attribute of a point format with two
// extra-bytes fields, with the write options that keep its records exact.
#pragma once

#include <tbb/task_arena.h>

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "core/binary_file.h"
#include "core/point_cloud.h"
#include "io/las/las_header.h"
#include "io/las/las_io.h"
#include "io/point_file.h"
#include "io/point_io.h"
#include "tests/util/test_util.h"

namespace candi::testing {

inline void Put16(uint8_t* p, uint32_t v) { StoreLE<uint16_t>(p, static_cast<uint16_t>(v)); }

// LAS records of `format` with `extra` extra bytes that look like a scan: a random walk with
// jumps, pulses of 1-5 returns sharing a GPS time, slowly changing attributes, grey and coloured
// points, scanner channels switching now and then.
inline std::vector<uint8_t> ScanLikeRecords(int format, int extra, size_t n, uint32_t seed) {
  const io::LasFormatLayout layout = io::LasLayoutOf(format);
  const size_t length = layout.record_size + extra;
  std::vector<uint8_t> records(n * length, 0);
  std::mt19937 rng(seed);
  auto chance = [&](int percent) { return static_cast<int>(rng() % 100) < percent; };
  int32_t x = 1000, y = -2000, z = 300;
  double time = 245000.0;
  uint32_t returns = 1, ret = 1, intensity = 500, cls = 2, user = 0, source = 7, channel = 0;
  int angle = 0;
  uint16_t rgb[4] = {1000, 2000, 3000, 4000};
  for (size_t i = 0; i < n; ++i) {
    uint8_t* p = records.data() + i * length;
    x += static_cast<int32_t>(rng() % 21) - 10 + (chance(1) ? static_cast<int32_t>(rng()) : 0);
    y += static_cast<int32_t>(rng() % 11) - 5;
    z += static_cast<int32_t>(rng() % 41) - 20;
    if (ret >= returns) {  // a new pulse
      returns = 1 + rng() % (chance(20) ? 5 : 1);
      ret = 1;
      time += chance(2) ? 1.0e4 * (rng() % 100) : 1.0e-5 * (1 + rng() % 3);
      if (chance(1)) time = -time;
    } else {
      ++ret;
    }
    if (chance(30)) intensity = (intensity + rng() % 200) & 0xFFFF;
    if (chance(5)) cls = rng() % (format >= 6 ? 256 : 32);
    if (chance(3)) user = rng() % 256;
    if (chance(1)) source = rng() % 65536;
    if (chance(10)) angle = static_cast<int>(rng() % 181) - 90;
    if (chance(2)) channel = rng() % 4;
    StoreLE<int32_t>(p, x);
    StoreLE<int32_t>(p + 4, y);
    StoreLE<int32_t>(p + 8, z);
    Put16(p + 12, intensity);
    const uint32_t flags = chance(5) ? rng() % 16 : 0;
    const uint32_t dir = rng() % 2, edge = chance(1) ? 1 : 0;
    if (format < 6) {
      p[14] = static_cast<uint8_t>(ret | returns << 3 | dir << 6 | edge << 7);
      p[15] = static_cast<uint8_t>(cls | (flags & 7) << 5);
      p[16] = static_cast<uint8_t>(static_cast<int8_t>(angle));
      p[17] = static_cast<uint8_t>(user);
      Put16(p + 18, source);
    } else {
      p[14] = static_cast<uint8_t>(ret | returns << 4);
      p[15] = static_cast<uint8_t>(flags | channel << 4 | dir << 6 | edge << 7);
      p[16] = static_cast<uint8_t>(cls);
      p[17] = static_cast<uint8_t>(user);
      Put16(p + 18, static_cast<uint32_t>(angle * 150));
      Put16(p + 20, source);
    }
    double t = time;
    if (layout.gps_offset >= 0) std::memcpy(p + layout.gps_offset, &t, 8);
    if (layout.color_offset >= 0) {
      if (chance(20)) {
        for (uint16_t& c : rgb) c = static_cast<uint16_t>(c + rng() % 512 - 256);
      }
      const bool grey = chance(10);
      for (int c = 0; c < 3; ++c) Put16(p + layout.color_offset + 2 * c, grey ? rgb[0] : rgb[c]);
      if (format == 8) Put16(p + layout.color_offset + 6, rgb[3]);
    }
    for (int e = 0; e < extra; ++e) {
      p[layout.record_size + e] = static_cast<uint8_t>(e == 0 ? i : chance(10) ? rng() : 3 * e);
    }
  }
  return records;
}

// A cloud of `n` points with every LAS attribute of `format` (from ScanLikeRecords through the
// LAS reader) and two extra-bytes fields.
inline PointCloud RandomCloud(int format, size_t n, uint32_t seed) {
  const io::LasFormatLayout layout = io::LasLayoutOf(format);
  PointCloud cloud;
  PointSchema schema;
  schema.colors = layout.color_offset >= 0;
  using namespace io::las_field;
  schema.scalars = {{kIntensity, ScalarType::kFloat32},
                    {kReturnNumber, ScalarType::kFloat32},
                    {kNumberOfReturns, ScalarType::kFloat32},
                    {kScanDirection, ScalarType::kFloat32},
                    {kEdgeOfFlightLine, ScalarType::kFloat32},
                    {kClassification, ScalarType::kFloat32},
                    {kClassFlags, ScalarType::kFloat32},
                    {kUserData, ScalarType::kFloat32},
                    {kPointSourceId, ScalarType::kFloat32},
                    {format >= 6 ? kScanAngle : kScanAngleRank, ScalarType::kFloat32}};
  if (layout.gps_offset >= 0) schema.scalars.push_back({kGpsTime, ScalarType::kFloat64});
  if (format >= 6) schema.scalars.push_back({kScannerChannel, ScalarType::kFloat32});
  if (format == 8) schema.scalars.push_back({kNir, ScalarType::kFloat32});
  schema.scalars.push_back({"confidence", ScalarType::kFloat32});
  schema.scalars.push_back({"range_m", ScalarType::kFloat64});
  cloud.SetSchema(schema);
  cloud.frame.origin = Eigen::Vector3d(500000.0, 4500000.0, 0.0);
  cloud.Resize(n);
  // Attribute values from scan-like records, decoded by the writer's inverse: written by hand.
  const std::vector<uint8_t> records = ScanLikeRecords(format, 0, n, seed);
  const size_t length = layout.record_size;
  std::mt19937 rng(seed);
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* p = records.data() + i * length;
    const Eigen::Vector3d world(500000.0 + 0.001 * LoadLE<int32_t>(p),
                                4500000.0 + 0.001 * LoadLE<int32_t>(p + 4),
                                0.001 * LoadLE<int32_t>(p + 8));
    cloud.positions[i] = cloud.frame.ToLocal(world);
    auto set = [&](const char* name, double v) { cloud.FindScalar(name)->Set(i, v); };
    set(kIntensity, LoadLE<uint16_t>(p + 12));
    const bool ext = format >= 6;
    set(kReturnNumber, ext ? p[14] & 15 : p[14] & 7);
    set(kNumberOfReturns, ext ? p[14] >> 4 : (p[14] >> 3) & 7);
    set(kScanDirection, ext ? (p[15] >> 6) & 1 : (p[14] >> 6) & 1);
    set(kEdgeOfFlightLine, ext ? p[15] >> 7 : p[14] >> 7);
    set(kClassification, ext ? p[16] : p[15] & 31);
    set(kClassFlags, ext ? p[15] & 15 : p[15] >> 5);
    set(kUserData, p[17]);
    set(kPointSourceId, LoadLE<uint16_t>(p + (ext ? 20 : 18)));
    if (ext) {
      set(kScanAngle, static_cast<int16_t>(LoadLE<uint16_t>(p + 18)));
      set(kScannerChannel, (p[15] >> 4) & 3);
    } else {
      set(kScanAngleRank, static_cast<int8_t>(p[16]));
    }
    if (layout.gps_offset >= 0) {
      double t;
      std::memcpy(&t, p + layout.gps_offset, 8);
      set(kGpsTime, t);
    }
    if (layout.color_offset >= 0) {
      const uint8_t* c = p + layout.color_offset;
      cloud.colors[i] =
          Rgb8{static_cast<uint8_t>(c[1]), static_cast<uint8_t>(c[3]), static_cast<uint8_t>(c[5])};
    }
    if (format == 8) set(kNir, LoadLE<uint16_t>(p + layout.color_offset + 6));
    set("confidence", (rng() % 1000) * 0.001);
    set("range_m", 10.0 + (rng() % 100000) * 1e-4);
  }
  return cloud;
}

inline io::PointWriteOptions OptionsFor(int format) {
  io::PointWriteOptions options;
  options.las_point_format = format;
  options.las_version_minor = format >= 6 ? 4 : 2;
  options.las_scale = Eigen::Vector3d::Constant(0.001);
  options.las_offset = Eigen::Vector3d(500000.0, 4500000.0, 0.0);
  return options;
}

// The bytes of `cloud` written to dir/one<ext> on one thread and to dir/two<ext> on two, with
// the creation day and year (bytes 90-93) zeroed: the runs may straddle midnight.
inline std::array<std::string, 2> WrittenOnOneAndTwoThreads(const TempDir& dir,
                                                            const std::string& ext,
                                                            const PointCloud& cloud,
                                                            const io::PointWriteOptions& options) {
  std::array<std::string, 2> bytes;
  for (int threads : {1, 2}) {
    const std::string path = dir.File((threads == 1 ? "one" : "two") + ext);
    tbb::task_arena(threads).execute([&] { io::WritePointCloud(path, cloud, options); });
    bytes[threads - 1] = ReadBytes(path);
    bytes[threads - 1].replace(90, 4, 4, '\0');
  }
  return bytes;
}

// True when a writer of dir/name destroyed after Write() and before Close() (an exception, an
// interrupt) leaves nothing in dir.
inline bool InterruptedWriteLeavesNothing(const TempDir& dir, const std::string& name,
                                          const PointCloud& cloud,
                                          const io::PointWriteOptions& options) {
  {
    auto writer = io::OpenPointWriter(
        dir.File(name), {cloud.schema, cloud.frame, cloud.meta, cloud.size()}, options);
    writer->Write(cloud);
  }
  return std::filesystem::is_empty(dir.path());
}

}  // namespace candi::testing

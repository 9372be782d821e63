// Writing E57 files with several scans, for tests and tools: poses, Cartesian or spherical
// coordinates, invalid-state fields and Integer, ScaledInteger or Float fields, each field coded
// exactly as asked (bitPackCodec), in the standard's layout: a 48-byte header, one
// CompressedVector section a scan, then the XML section; every 1024-byte page ends with its
// CRC-32C. For writing a point cloud, use OpenE57Writer (io/e57/e57_io.h).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace candi::io {

enum class E57FieldType {
  kFloat,          // IEEE single precision
  kDouble,         // IEEE double precision
  kInteger,        // integer in [minimum, maximum]
  kScaledInteger,  // raw integer in [minimum, maximum]; value = raw * scale + offset
};

struct E57Field {
  std::string name;  // E57 element name: "cartesianX", "sphericalRange", "intensity", "colorRed", ...
  E57FieldType type = E57FieldType::kDouble;
  int64_t minimum = 0, maximum = 0;  // Integer / ScaledInteger raw bounds (minimum <= maximum)
  double scale = 1.0, offset = 0.0;  // ScaledInteger (scale != 0)
  // One value a record: the value itself (Integer: rounded; ScaledInteger: the scaled value,
  // stored as round((value - offset) / scale)). A value outside the bounds is std::invalid_argument.
  std::vector<double> values;
};

struct E57Scan {
  std::string name;  // optional
  std::string guid;  // empty: generated
  // Pose: file frame = rotation * scan frame + translation.
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  std::vector<E57Field> fields;  // all with the same number of values (the record count)
  std::optional<Eigen::Vector2d> intensity_limits;  // intensityMinimum, intensityMaximum
  std::optional<Eigen::Vector2d> color_limits;      // the same minimum, maximum for R, G, B
};

struct E57WriteOptions {
  std::string guid;                 // file GUID; empty: generated
  std::string coordinate_metadata;  // /coordinateMetadata (e.g. OGC WKT); empty: none
  size_t packet_records = 0;        // records a data packet at most; 0: fill packets to 64 KiB
  void Check() const {}             // every value is valid
};

// Writes `scans` to `path` atomically. Throws std::invalid_argument for a scan without fields,
// fields of different lengths or values out of range, InputError for I/O failures.
void WriteE57(const std::string& path, const std::vector<E57Scan>& scans,
              const E57WriteOptions& options = {});

}  // namespace candi::io

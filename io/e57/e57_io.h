// E57 (ASTM E2807, the laser-scan exchange format) point reading and writing.
//
// Reading: every scan of /data3D is read, one after the other, into one stream of points in the
// file's frame: each scan's pose (rotation quaternion w, x, y, z, then translation) is applied, so
// positions are world coordinates in double (frame zero, like LAS). Per scan:
//  - position: cartesianX/Y/Z, or sphericalRange/Azimuth/Elevation converted with
//    x = r cos(el) cos(az), y = r cos(el) sin(az), z = r sin(el) (radians, metres);
//  - cartesianInvalidState / sphericalInvalidState: points whose state is not 0 (1: direction
//    only, 2: no position) are dropped, because a point cloud has no place for a point without a
//    position;
//  - colorRed/Green/Blue → 8-bit colour, (value - min) * 255 / (max - min) rounded, with min/max
//    from colorLimits, else from the fields' Integer limits; isColorInvalid != 0 gives the
//    default colour;
//  - intensity → float scalar "intensity", the raw value (intensityLimits are not applied);
//    isIntensityInvalid != 0 gives 0;
//  - timeStamp → double scalar "time_stamp" (isTimeStampInvalid != 0 gives 0);
//  - other fields (returnIndex, rowIndex, las:*, ...) are decoded past and dropped.
// Schema: colours when any scan has them (scans without get the default grey 128, 128, 128);
// "intensity" when any scan has it, "time_stamp" likewise (0 where a scan lacks them).
// PointReadOptions::scalar_fields = false skips intensity and time stamps. info().count is the sum
// of the scans' recordCounts, or kUnknownCount when any scan has an invalid-state field (then Read
// may return fewer points than the records). meta.crs is /coordinateMetadata; meta.comments hold
// "e57 scan <i>: <name>" lines. images2D, and codecs other than bitPackCodec, are not supported:
// images are ignored (logged), another codec is an InputError naming its XML element.
// Memory is bounded: packets are read in order and each field's bytes queued until every field
// can give values; more than 256 MiB queued (badly interleaved streams) is an InputError.
// Every page read has its CRC-32C checked. Bad input throws InputError("<path>: byte N: ..." or
// "<path>: XML line N, <element>: ...").
//
// Writing (OpenE57Writer): one scan, Cartesian coordinates in the spec's frame with the frame's
// origin as the scan pose's translation (so readers see world coordinates). Precision: double for
// PositionPrecision::kFloat64, or kAuto with a shifted frame or double positions; single
// otherwise. Colours become colorRed/Green/Blue Integer 0-255 with colorLimits 0-255; a scalar
// field "intensity" becomes a single-precision Float intensity with intensityLimits from the data;
// "time_stamp" becomes a double timeStamp; other scalar fields and normals are not written (logged).
// The binary section is written as points come; the XML and header at Close(); atomic (temporary
// file, then rename). Several scans, poses, spherical coordinates and integer codings: see
// io/e57/e57_writer.h.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "io/point_file.h"

namespace candi::io {

std::unique_ptr<PointReader> OpenE57Reader(const std::string& path,
                                           const PointReadOptions& options = {});
// The scans of an E57 file as its XML states them (no point is read): name (or GUID), pose (file
// frame = rotation * scan frame + translation) and record count. InputError as the reader.
struct E57ScanInfo {
  std::string name;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  uint64_t records = 0;
};
std::vector<E57ScanInfo> ListE57Scans(const std::string& path);

// One scan of an E57 file, in the scan's own frame (its pose not applied), for registration
// (the pose is then its start). `scan` must be below the file's scan count (InputError naming it).
std::unique_ptr<PointReader> OpenE57ScanReader(const std::string& path, size_t scan,
                                               const PointReadOptions& options = {});

std::unique_ptr<PointWriter> OpenE57Writer(const std::string& path, const PointWriteSpec& spec,
                                           const PointWriteOptions& options = {});

}  // namespace candi::io

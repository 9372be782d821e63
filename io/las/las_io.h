// LAS 1.2-1.4 reading and writing (ASPRS LAS specification R15).
//
// Point formats 0-3 and 6-8. Positions are world coordinates X*scale + offset in double (frame
// zero); scale, offset, version, point format, header fields and VLRs/EVLRs are kept in
// meta.las so a rewrite preserves them. The standard attributes become scalar fields with the
// names below (all exact in float except gps_time, which is double). Colour: 16-bit values are
// reduced to 8 bits (v >> 8) unless every value in the file fits in 8 bits (files that store
// 8-bit colour in the 16-bit fields), detected from the data and recorded in meta.las.color_16bit.
// Uncompressed records are read in place (core/mapped_file.h) and decoded in parallel blocks.
// Extra bytes (LAS 1.4 "LASF_Spec" record 4) of numeric types become scalar fields; normals are
// written and read as the extra-bytes fields "nx", "ny", "nz".
//
// LAZ (LASzip-compressed LAS: format byte bits 6-7 and a "laszip encoded" VLR) reads through the
// same reader: the chunked pointwise compressor (items of version 2, formats 0-3) and the layered
// one (version 3, formats 6-8) are decoded (io/laz/laz_format.h, io/laz/laz_chunks.h), a run of
// chunks at a time and in parallel; LASzip 1.x files (items of version 1, the unchunked
// compressor), waveform items and files without a chunk table are refused with a clear message.
// meta.las holds the uncompressed point format and no laszip VLR; record_layout() is nullopt.
// Writing to a .laz name writes LAZ as LASzip 3.4 does (point-format bit 7, the laszip VLR last,
// 50,000-point chunks with the chunk table, compressed in parallel; io/laz/laz_chunks.h), with
// the same header, VLRs and records as the LAS file the name .las would give.
// A name ending in .copc.laz writes COPC 1.0 (https://copc.io): LAS 1.4 with point format 6-8
// (formats 0-3 become 6 or 7, as PDAL's writers.copc does), the "copc" info VLR first, the octree
// of io/copc/copc_octree.h with each node one variable-size layered LAZ chunk, and the hierarchy
// EVLR in pages as untwine cuts them (io/copc/copc_write.h, PointWriteOptions::copc); the source's "copc" records are dropped, and GeoTIFF-key CRS
// records give way to a WKT record of the CRS they name (formats 6-8 allow only WKT). Its
// records are held in memory until Close() (record_length bytes a point).
//
// Reading: the whole header, VLRs and EVLRs are parsed and validated at open (a truncated file,
// bad signature, unsupported point format, short record length or zero scale throws InputError
// naming the byte); files with colour are scanned once at open for the 8/16-bit test. Extra-bytes
// fields become float, or double for 32/64-bit integers, doubles and scaled values; undocumented
// bytes and arrays are skipped. Read() decodes column by column (one strided loop per attribute).
//
// Writing: the version and point format are PointWriteOptions::las_version_minor/las_point_format
// when set (std::invalid_argument when the format cannot hold the points' colours, gps_time, nir
// or scanner_channel, or needs LAS 1.4); else meta.las's when they hold exactly the points'
// attributes; else LAS 1.2 format 0-3, or 1.4 format 6-8 for scanner_channel, nir or more than
// 2^32-1 points. Scale: option, meta.las, else 0.001 m; offset: option, meta.las, the spec's
// frame origin (rounded), else LocalFrame::Auto of the first chunk. Standard attributes are
// rounded and clamped into their fields (missing: 0, one return); scan_angle and scan_angle_rank
// are converted between formats; other scalar fields and normals become float/double extra bytes.
// EVLRs stay EVLRs in 1.4 and become VLRs before 1.4 when they fit (else dropped with a warning).
// A coordinate outside int32 after scale/offset throws InputError naming the point.
#pragma once

#include <memory>
#include <string>

#include "io/point_file.h"

namespace candi::io {

// Scalar field names used for the LAS standard attributes.
namespace las_field {
inline constexpr const char* kIntensity = "intensity";
inline constexpr const char* kReturnNumber = "return_number";
inline constexpr const char* kNumberOfReturns = "number_of_returns";
inline constexpr const char* kScanDirection = "scan_direction_flag";
inline constexpr const char* kEdgeOfFlightLine = "edge_of_flight_line";
inline constexpr const char* kClassification = "classification";      // 0-255 (formats 0-3: 0-31)
inline constexpr const char* kClassFlags = "classification_flags";     // synthetic/keypoint/withheld/overlap bits
inline constexpr const char* kScannerChannel = "scanner_channel";      // formats 6-8
inline constexpr const char* kUserData = "user_data";
inline constexpr const char* kScanAngleRank = "scan_angle_rank";       // formats 0-3, degrees (int8)
inline constexpr const char* kScanAngle = "scan_angle";                // formats 6-8, units of 0.006 deg (int16)
inline constexpr const char* kPointSourceId = "point_source_id";
inline constexpr const char* kGpsTime = "gps_time";                    // double
inline constexpr const char* kNir = "nir";                             // format 8
}  // namespace las_field

std::unique_ptr<PointReader> OpenLasReader(const std::string& path,
                                           const PointReadOptions& options = {});
std::unique_ptr<PointWriter> OpenLasWriter(const std::string& path, const PointWriteSpec& spec,
                                           const PointWriteOptions& options);

}  // namespace candi::io

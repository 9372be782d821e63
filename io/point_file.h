// Point files: the streaming reader and writer interfaces every format implements (io/las,
// io/e57, io/ply, io/xyz), what a reader reports about a file, and the read and write options.
// io/point_io.h opens a file of any format through them.
//
// Formats: PLY (ascii, binary little/big endian), LAS 1.2-1.4 (point formats 0-3, 6-8), XYZ and
// PTS text, LAZ (compressed LAS, read only; PointFormat::kLas) and E57 (ASTM E2807 laser scans,
// io/e57/e57_io.h). The format is chosen by extension and confirmed by the content; a mismatch and
// DXF are errors, not guesses. Readers and writers stream: a file larger than memory is processed
// chunk by chunk, counts are 64-bit. Writers are atomic (temporary file, then rename on Close()).
// Bad input throws InputError("<path>: <position>: <what>").
//
// Frames: a reader reports the shift recorded with the file (PLY comment "candi_shift x y z", or
// the sidecar "<path>.shift.json" written beside shifted non-LAS outputs); LAS positions are read
// as world coordinates (frame zero) with scale/offset kept in meta.las. A writer writes points in
// the frame of its PointWriteSpec (chunks in another frame are re-expressed, exactly for integer
// shifts); LAS always stores world coordinates.
#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>

#include "core/point_cloud.h"
#include "core/progress.h"
#include "io/point_format.h"

namespace candi::io {

constexpr uint64_t kUnknownCount = std::numeric_limits<uint64_t>::max();

struct PointFileInfo {
  PointFormat format = PointFormat::kPly;
  std::string description;     // e.g. "PLY binary_little_endian 1.0", "LAS 1.4 point format 7"
  uint64_t count = kUnknownCount;  // points in the file (kUnknownCount for text until read)
  PointSchema schema;          // attributes of each point
  LocalFrame frame;            // shift recorded with the file
  PointCloudMeta meta;         // comments, LAS metadata
  std::optional<Box3d> header_bounds;  // world bounds stated in the header (LAS)
  uint64_t face_count = 0;     // PLY faces (the point reader skips them)
};

struct PointReadOptions {
  // XYZ/PTS column spec, comma separated: x y z (required), r g b (0-255), nx ny nz, i
  // (intensity), a name (a float scalar field of that name) or _ (skip). Empty: guessed from the
  // first data line and logged.
  std::string columns;
  // false: scalar fields are not decoded (LAS attributes and extra bytes, other PLY properties,
  // other XYZ columns); geometry, colours and normals only. Faster, for rendering and viewing.
  bool scalar_fields = true;
  // Every value is valid here: `columns` is parsed, and a bad spec refused naming its entry, by
  // the XYZ/PTS reader when it opens (other formats do not read it), as PointWriteOptions::columns
  // is by the writer.
  void Check() const {}
};

// How a file stores its points when they are fixed-size little-endian records: binary
// little-endian PLY whose vertices have float or double x, y, z (all three of one type), uchar
// colour (or none) and no lists, and LAS (int32 X, Y, Z with the header's scale and offset, 16-bit
// colour). A consumer that needs only positions and colours (the render archive packer, the
// streaming renderer) decodes such records itself, in bulk and in parallel, where Read() would
// copy every point into a chunk first. A record's position in the reader's info().frame is
// (double(x), double(y), double(z)) for floats and doubles and LasPositionDecoder(scale, offset)
// of the integers for LAS; its colour (red, green, blue) is the bytes at rgb, or the 16-bit values
// there >> color_shift (default colour when rgb[0] < 0): what Read() gives.
struct PointRecordLayout {
  enum class Coordinates { kFloat32, kFloat64, kLasInt32 };
  Coordinates coordinates = Coordinates::kFloat32;
  uint64_t first_byte = 0;       // file offset of the first record
  size_t stride = 0;             // bytes a record
  size_t xyz[3] = {0, 0, 0};     // offsets of x, y, z in a record
  int rgb[3] = {-1, -1, -1};     // offsets of red, green, blue; -1: no colour
  int color_bytes = 1;           // 1 (8-bit) or 2 (16-bit, LAS)
  int color_shift = 0;           // 16-bit colour: value >> color_shift
  Eigen::Vector3d scale = Eigen::Vector3d::Ones(), offset = Eigen::Vector3d::Zero();  // LAS
  uint64_t count = 0;            // records
};

class PointReader {
 public:
  virtual ~PointReader() = default;
  const PointFileInfo& info() const { return info_; }
  const std::string& path() const { return path_; }
  // Reads up to max_points (> 0) next points into *chunk, replacing its points; chunk's schema,
  // frame and meta are set from info(). Returns the number read, 0 at the end of the points.
  virtual size_t Read(size_t max_points, PointCloud* chunk) = 0;
  // The file's point records when their layout is a PointRecordLayout, else nullopt. The caller
  // reads the bytes itself (and checks that the file holds them all).
  virtual std::optional<PointRecordLayout> record_layout() const { return std::nullopt; }
  uint64_t points_read() const { return points_read_; }

 protected:
  PointReader(std::string path) : path_(std::move(path)) {}
  // Prepares *chunk for refilling with the file's schema.
  void PrepareChunk(PointCloud* chunk) const;
  std::string path_;
  PointFileInfo info_;
  uint64_t points_read_ = 0;
};

enum class PlyEncoding { kBinaryLittleEndian, kBinaryBigEndian, kAscii };
enum class PositionPrecision { kAuto, kFloat32, kFloat64 };

// COPC (a *.copc.laz name, io/copc/copc_write.h) writing options.
struct CopcWriteOptions {
  // The hierarchy's pages as untwine and PDAL cut them: a page holds its root node and this many
  // levels below it; a node at that depth whose subtree has more than min_page_nodes nodes
  // starts a child page (entry point count -1). 4 and 50 as untwine (LevelBreak,
  // MinHierarchySize); page_levels >= 1, min_page_nodes >= 0 (1 and 0: a page a node with
  // children one level down, for tests).
  int page_levels = 4;
  int min_page_nodes = 50;
  // The memory the records may take until Close() builds the octree (about the record length
  // + 16 bytes a point); beyond it they are spilled to a temporary folder beside the file (its
  // disk needs about twice the records' size) and the octree is built from there, the same
  // bytes. 0: half this machine's physical memory.
  uint64_t memory_bytes = 0;
  void Check() const;
};

struct PointWriteOptions {
  PlyEncoding ply_encoding = PlyEncoding::kBinaryLittleEndian;
  // PLY/XYZ position precision. kAuto: double when the spec's frame has a shift or the schema's
  // position_type is double, float otherwise (so nothing is lost).
  PositionPrecision precision = PositionPrecision::kAuto;
  // LAS: -1 = keep meta.las when present, else choose (1.2, format 0/2 or 1/3; 1.4 when needed).
  int las_version_minor = -1;   // 2, 3 or 4
  int las_point_format = -1;    // 0-3, 6-8
  std::optional<Eigen::Vector3d> las_scale;   // default: meta.las.scale if present, else 0.001 m
  std::optional<Eigen::Vector3d> las_offset;  // default: meta.las.offset if present, else frame origin
  // XYZ/PTS: column spec as in PointReadOptions; empty = all of the schema (x,y,z[,r,g,b][,nx,ny,nz][,scalars]).
  std::string columns;
  CopcWriteOptions copc;
  // The work Close() does after the last Write, by stage, as (stage, done, total): a COPC
  // file's "octree" (points placed in their buckets, of all) then "chunks" (points whose node is
  // built and compressed).
  // Called on the thread that calls Close(); null: not reported.
  StageProgressCallback close_progress;
  void Check() const;
};

struct PointWriteSpec {
  PointSchema schema;
  LocalFrame frame;       // the frame the output is written in
  PointCloudMeta meta;
  uint64_t count = kUnknownCount;  // number of points that will be written, if known
};

class PointWriter {
 public:
  // Destroying a writer without Close() discards the output: the destination stays as it was.
  virtual ~PointWriter() = default;
  // Appends chunk (its schema must equal the spec's; its frame may differ).
  virtual void Write(const PointCloud& chunk) = 0;
  // Completes the file (patches counts and bounds) and renames it into place.
  virtual void Close() = 0;
  uint64_t points_written() const { return points_written_; }

 protected:
  uint64_t points_written_ = 0;
};

}  // namespace candi::io

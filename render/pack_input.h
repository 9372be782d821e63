// The packer's reading of its inputs (render/archive_pack.cc), private to it: the points as
// records in the archive frame, batch by batch, and the direct reading of files whose points are
// fixed-size records (io/point_io.h's PointRecordLayout): binary PLY of floats, which pass 1
// scans for bounds and the manifest's hash in one read and pass 2 turns into CompactPoints
// without widening every coordinate to a double, and LAS, turned into LasPoints.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/box.h"
#include "core/mapped_file.h"
#include "io/las/las_columns.h"
#include "io/point_io.h"
#include "render/archive_pack.h"
#include "render/pack_records.h"
#include "render/splat_cloud.h"

namespace candi::render::pack_internal {

// HashFile hashes files in blocks of this many bytes.
constexpr size_t kHashBlock = size_t{64} << 20;

// The records of a PointRecordLayout read straight from the file, block by block (parallel
// preads). Refuses (InputError naming the file and the vertex) a file too short for them.
class RecordFile {
 public:
  RecordFile(const std::string& path, const io::PointRecordLayout& layout);
  ~RecordFile();
  RecordFile(const RecordFile&) = delete;
  RecordFile& operator=(const RecordFile&) = delete;
  const io::PointRecordLayout& layout() const { return layout_; }
  // Reads up to max_points next records; returns how many (0 at the end), at *records.
  size_t Next(size_t max_points, const uint8_t** records);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  io::PointRecordLayout layout_;
  uint64_t next_ = 0;
};

// Pass 1 over a file of records of floats or doubles (binary PLY): the world bounds of its
// points (world = frame origin + position), whether every coordinate is a float (doubles that a
// float holds exactly), and HashFile's hash and size, from one read. A NaN or infinite
// coordinate is refused as the readers refuse it ("vertex N: coordinate is NaN or infinite").
struct RecordScan {
  Box3d world;
  bool floats = true;
  uint64_t hash = 0, bytes = 0;
  std::shared_ptr<const MappedFile> map;  // the file's map, which pass 2 shares while it is held
};
RecordScan ScanRecords(const std::string& path, const io::PointRecordLayout& layout, const LocalFrame& frame);

// Reads all inputs as points P in the archive frame (CompactPoints: in their shared frame),
// ~2^20 points a batch. Files of records are read directly (`direct`, PackOptions::direct_reads):
// binary PLY of floats as CompactPoints, LAS as LasPoints (only so).
template <typename P>
class InputBatches {
 public:
  // compact_origin: CompactPoint's frame, the one all inputs share.
  // las: LasPoint's decoder, the one all inputs share.
  InputBatches(const std::vector<PackInput>& inputs, const LocalFrame& frame, Rgb8 default_color,
               const Eigen::Vector3d& compact_origin, const io::LasPositionDecoder& las, bool direct);
  ~InputBatches();
  // The next batch into *out; false after the last.
  bool operator()(UninitVector<P>* out);

 private:
  // Reads the records of the current input (a RecordFile) into *out.
  bool ReadRecords(UninitVector<P>* out);

  const std::vector<PackInput>& inputs_;
  LocalFrame frame_;
  Rgb8 default_color_;
  Eigen::Vector3d compact_origin_;
  io::LasPositionDecoder las_;
  bool direct_;
  size_t next_ = 0;
  uint64_t index_ = 0;
  std::unique_ptr<io::PointReader> reader_;
  std::unique_ptr<RecordFile> records_;
  PointCloud chunk_;
};

}  // namespace candi::render::pack_internal

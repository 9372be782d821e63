// Internal to the LAS writer (io/las/las_writer.cc): a COPC file's records from the first Write to
// Close(), which builds the octree over them (io/copc/copc_octree.h). In memory while they fit the
// budget (CopcWriteOptions::memory_bytes; 0: half this machine's memory), at about the record
// length + 16 bytes a point with the octree's lists; beyond it, spilled to a temporary folder
// beside the file (PATH.candi-tmp-copc-XXXXXX, registered with the interrupt handler and removed
// with the store), whose disk then needs about twice the records. A stated count the disk cannot
// hold is refused by the constructor, before anything is written. The records' GPS time range
// (the COPC info VLR's) is kept as they come.
// Failure: InputError naming the file (disk, the folder, a spill write). Not thread-safe.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "core/fresh_memory.h"
#include "core/interrupt.h"
#include "core/spill_file.h"
#include "io/copc/copc_octree.h"
#include "io/point_file.h"

namespace candi::io {

class CopcRecordStore {
 public:
  // `stated`: the count the writer was told (kUnknownCount: none).
  CopcRecordStore(const std::string& path, size_t record_length, size_t gps_offset,
                  const CopcWriteOptions& options, uint64_t stated);
  bool spilled() const { return spill_ != nullptr; }
  // In memory: room for n more records (their bytes undefined), for the caller to encode then
  // Add(). Spilled: null.
  uint8_t* Extend(size_t n);
  // n records the caller has encoded, at `records`: in the memory Extend gave, or (spilled) in
  // a buffer of its own, appended here.
  void Add(const uint8_t* records, size_t n);
  // The records for the octree (valid until Release).
  CopcRecords Records();
  // The info VLR's GPS range ({0, 0} when no record has a time).
  std::array<double, 2> GpsTimes() const;
  void Release();

 private:
  void Spill();

  const std::string path_;
  const size_t length_, gps_offset_;
  uint64_t memory_ = 0;
  FreshBuffer records_;
  TempFolder folder_;  // the spill's, once spilled
  std::unique_ptr<SpillFile> spill_;
  std::array<double, 2> gps_{INFINITY, -INFINITY};
};

}  // namespace candi::io

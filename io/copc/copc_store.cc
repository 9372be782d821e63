#include "io/copc/copc_store.h"

#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <limits>
#include <system_error>

#include "core/check.h"
#include "core/interrupt.h"
#include "core/log.h"
#include "core/text_format.h"
#include "io/copc/copc_write.h"

namespace candi::io {

CopcRecordStore::CopcRecordStore(const std::string& path, size_t record_length, size_t gps_offset,
                                 const CopcWriteOptions& options, uint64_t stated)
    : path_(path), length_(record_length), gps_offset_(gps_offset) {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  const double physical =
      pages > 0 && page > 0 ? static_cast<double>(pages) * static_cast<double>(page) : 0.0;
  // Half the machine's memory unless given; where the machine does not say, all of it can be.
  memory_ = options.memory_bytes > 0 ? options.memory_bytes
            : physical > 0           ? static_cast<uint64_t>(physical / 2)
                                     : std::numeric_limits<uint64_t>::max();
  if (stated == kUnknownCount) return;  // in memory until they no longer fit
  // In memory: the records, each point's cell then its place in its bucket's list, and the
  // points of the nodes above the buckets (io/copc/copc_octree.h).
  const double length = static_cast<double>(length_), count = static_cast<double>(stated);
  if (count * (length + 16) <= static_cast<double>(memory_)) {
    records_.Reserve(stated * length_);
    return;
  }
  Spill();
  // Spilled: the records, then their groups (the spill's blocks given back as they are read,
  // where the filesystem can) and the points above the buckets: twice the records at most.
  struct statvfs disk;
  if (statvfs(folder_.path().c_str(), &disk) != 0) return;
  const double free = static_cast<double>(disk.f_bavail) * static_cast<double>(disk.f_frsize);
  const double needed = 2.0 * count * length;
  if (needed <= free) return;
  constexpr double kGiB = double(uint64_t{1} << 30);
  throw InputError(path_, "",
                   "a COPC file of " + std::to_string(stated) + " points holds its " +
                       "records until its octree is built: more than the memory it may take (" +
                       FormatSignificant(static_cast<double>(memory_) / kGiB, 3) +
                       " GiB), and spilled beside the file they need about " +
                       FormatSignificant(needed / kGiB, 3) + " GiB of disk, where " +
                       FormatSignificant(free / kGiB, 3) +
                       " GiB are free: write LAZ (a .laz name), or fewer points a file");
}

// A folder beside the file, for the records and the octree's own files; the records held so
// far go there first.
void CopcRecordStore::Spill() {
  const std::filesystem::path target(path_);
  const std::filesystem::path folder =
      target.has_parent_path() ? target.parent_path() : std::filesystem::path(".");
  std::string pattern = (folder / (target.filename().string() + ".candi-tmp-copc-XXXXXX")).string();
  const int id = MakeTempDirectory(&pattern);
  if (id < 0) {
    throw InputError(
        pattern, "",
        std::string("cannot create the COPC file's spill folder: ") + std::strerror(errno));
  }
  folder_.Reset(pattern, id);
  LogInfo(path_ + ": the COPC file's records pass its memory budget (" +
          FormatSignificant(static_cast<double>(memory_) / 1048576.0, 4) + " MB): spilled to " +
          pattern + " until the file is complete");
  spill_ = std::make_unique<SpillFile>(pattern + "/records");
  if (records_.size() > 0) {
    spill_->Append(records_.data(), records_.size());
    records_.Release();
  }
}

uint8_t* CopcRecordStore::Extend(size_t n) {
  return spilled() ? nullptr : records_.Extend(n * length_);
}

void CopcRecordStore::Add(const uint8_t* records, size_t n) {
  ExtendCopcGpsTimeRange(records, n, length_, gps_offset_, &gps_);
  if (spilled()) {
    spill_->Append(records, n * length_);
  } else if (records_.size() / length_ * (length_ + 16) > memory_) {
    Spill();  // a count not stated beforehand: no longer in memory
  }
}

CopcRecords CopcRecordStore::Records() {
  CopcRecords records;
  records.record_length = length_;
  if (spilled()) {
    records.spill = spill_.get();
    records.n = spill_->size() / length_;
    records.spill_dir = folder_.path();
    // A group's records (mapped from its file), their lists and cells.
    records.memory_points = std::max<uint64_t>(1, memory_ / (length_ + 8));
  } else {
    records.data = records_.data();
    records.n = records_.size() / length_;
  }
  return records;
}

std::array<double, 2> CopcRecordStore::GpsTimes() const { return CopcGpsTimes(gps_); }

void CopcRecordStore::Release() {
  records_.Release();
  spill_.reset();
}

}  // namespace candi::io

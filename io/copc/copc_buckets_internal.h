// Internal to io/copc (copc_buckets.cc, copc_nodes.cc): the cube of a COPC octree cut into
// buckets (io/copc/copc_octree.h) by the counts of its cells at level 7, the flat indices of the
// nodes that can be above a bucket, and, for records spilled to disk, the groups of consecutive
// buckets that are built one at a time from files of their own.
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/binary_file.h"
#include "core/spill_file.h"
#include "io/copc/copc_octree.h"
#include "io/copc/copc_octree_internal.h"

namespace candi::io::copc_internal {

// Buckets are nodes of levels 0..kBucketLevel; the points' cells there are counted. A node above
// a bucket (level < kBucketLevel) has its cells (kCellBits levels down) whole in the bucket.
constexpr int kBucketLevel = 7;
static_assert(kBucketLevel <= kCellBits);
constexpr uint32_t kCells = uint32_t{1} << (3 * kBucketLevel);

// The nodes that can be above a bucket (levels 0..kBucketLevel - 1) by a flat index: level k's
// 8^k (by Morton code) after the levels above.
inline uint32_t LevelStart(int level) { return ((uint32_t{1} << (3 * level)) - 1) / 7; }
constexpr uint32_t kAboveNodes = (kCells - 1) / 7;
inline uint32_t AboveIndex(int level, uint32_t code) { return LevelStart(level) + code; }
int LevelOfIndex(uint32_t index);

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// The key of the node of Morton code `code` at `level` (its octants, level 1's highest).
CopcKey KeyOf(int level, uint32_t code);

// A bucket: node (level, code) and its points, list[begin, end) in input order.
struct Bucket {
  int level = 0;
  uint32_t code = 0;
  size_t begin = 0, end = 0;
  size_t size() const { return end - begin; }
};

// The code of the bucket's ancestor at `level` (<= its level).
inline uint32_t AncestorCode(const Bucket& b, int level) {
  return b.code >> (3 * (b.level - level));
}

// A record's X, Y, Z.
inline void LoadXyz(const uint8_t* record, int32_t* xyz) {
  for (int k = 0; k < 3; ++k) xyz[k] = LoadLE<int32_t>(record + 4 * k);
}

// The deepest level a bucket may have: kBucketLevel, or the first level whose cells are
// narrower than a LAS unit (whose nodes keep all their points: no node above a bucket may).
int DeepestBucketLevel(const CopcOctree& tree, double min_scale);

// A record's cell at kBucketLevel: the top 7 bits of each axis's place, floor(t * 128) clamped
// (the place's bits 55-61: t is computed as the Cube computes it, and t * 2^7 is exact), spread
// by a table into a Morton code.
struct CellTable {
  uint32_t spread[1 << kBucketLevel];
  CellTable() {
    for (uint32_t v = 0; v < (1u << kBucketLevel); ++v) {
      spread[v] = static_cast<uint32_t>(MortonSpread21(v));
    }
  }
};
inline const CellTable kCellTable;
inline uint32_t CellOf(const uint8_t* record, const Cube& cube) {
  uint32_t cell = 0;
  for (int k = 0; k < 3; ++k) {
    const double t =
        (LoadLE<int32_t>(record + 4 * k) * cube.scale[k] + cube.offset[k] - cube.min[k]) /
        cube.width;
    const double u = t * double{1 << kBucketLevel};
    const uint32_t q = !(u > 0.0)                       ? 0u
                       : u >= double{1 << kBucketLevel} ? (1u << kBucketLevel) - 1
                                                        : static_cast<uint32_t>(u);
    cell |= kCellTable.spread[q] << k;
  }
  return cell;
}

// A record's bytes copied (length >= 8, whatever it is: in 8-byte words, the last overlapping),
// without a call.
inline void CopyRecord(uint8_t* to, const uint8_t* from, size_t length) {
  size_t k = 0;
  for (; k + 8 <= length; k += 8) std::memcpy(to + k, from + k, 8);
  if (k < length) std::memcpy(to + length - 8, from + length - 8, 8);
}

// The points of each cell at kBucketLevel, counted run by run of records, by parallel blocks
// into each thread's counts (sums: the same on any thread count); each point's cell into
// cells[i] unless cells is null.
class CellCounter {
 public:
  explicit CellCounter(const Cube& cube) : cube_(cube) {}
  void Add(const uint8_t* records, size_t n, size_t length, uint32_t* cells);
  std::vector<uint64_t> Counts() const;

 private:
  const Cube cube_;
  tbb::enumerable_thread_specific<std::vector<uint32_t>> local_{
      [] { return std::vector<uint32_t>(kCells, 0); }};
};

// The records of a spill read in order, a run at a time, into a buffer (so the spill is never
// all in memory); with `discard`, each run's disk blocks are given back once it is read.
class SpillRuns {
 public:
  SpillRuns(SpillFile* spill, size_t length, bool discard);
  // The next run (its first record's index and count); false at the end.
  bool Next(const uint8_t** records, size_t* first, size_t* count);

 private:
  static constexpr size_t kRunPoints = size_t{1} << 18;
  SpillFile* const spill_;
  const size_t length_;
  const bool discard_;
  std::unique_ptr<uint8_t[]> buffer_;
  uint64_t at_ = 0;
};

// The buckets (in Morton order) of points counted by cell: the nodes of more than max_points
// points split down to max_level; their sizes in `end` (begin 0). bucket_of[cell]: the bucket
// holding a cell (kNone for an empty one).
std::vector<Bucket> ChooseBuckets(const std::vector<uint64_t>& cell_counts, size_t max_points,
                                  int max_level, std::vector<uint32_t>* bucket_of);

// The n points (cells[i] their cells, all in buckets [first, first + count) of bucket_of) listed
// by bucket into list[0, n), each bucket's in input order whatever the thread count. Sets the
// buckets' begin and end.
void ListByBucket(const uint32_t* cells, size_t n, const std::vector<uint32_t>& bucket_of,
                  size_t first, size_t count, Bucket* buckets, uint32_t* list);

// A group of consecutive buckets of a spilled build: its records and their indices (in input
// order) in files of its own.
struct GroupFiles {
  size_t first = 0, count = 0;  // its buckets
  std::unique_ptr<SpillFile> records;
  std::unique_ptr<SpillRecords<uint32_t>> indices;
};

// The spill's records to groups of consecutive buckets of at most max_points points (or one
// bucket), their files in `dir`: the spill read once in order, its blocks given back as read.
std::vector<GroupFiles> RouteToGroups(SpillFile* spill, size_t length, const Cube& cube,
                                      const std::vector<Bucket>& buckets,
                                      const std::vector<uint32_t>& bucket_of, size_t max_points,
                                      const std::string& dir);

}  // namespace candi::io::copc_internal

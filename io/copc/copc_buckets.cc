// The cut of a COPC octree's cube into buckets (copc_buckets_internal.h).
#include "io/copc/copc_buckets_internal.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>

#include "core/check.h"
#include "core/parallel.h"

namespace candi::io::copc_internal {

int LevelOfIndex(uint32_t index) {
  int level = 0;
  while (level + 1 < kBucketLevel && LevelStart(level + 1) <= index) ++level;
  return level;
}

CopcKey KeyOf(int level, uint32_t code) {
  CopcKey key{level, 0, 0, 0};
  for (int l = level - 1; l >= 0; --l) {
    const uint32_t o = code >> (3 * l) & 7;
    key.x = 2 * key.x + static_cast<int32_t>(o & 1);
    key.y = 2 * key.y + static_cast<int32_t>(o >> 1 & 1);
    key.z = 2 * key.z + static_cast<int32_t>(o >> 2 & 1);
  }
  return key;
}

int DeepestBucketLevel(const CopcOctree& tree, double min_scale) {
  for (int level = 0; level < kBucketLevel; ++level) {
    if (std::ldexp(tree.spacing, -level) < min_scale) return level;
  }
  return kBucketLevel;
}

void CellCounter::Add(const uint8_t* records, size_t n, size_t length, uint32_t* cells) {
  ParallelFor(size_t{0}, (n + kBlock - 1) / kBlock, [&](size_t b) {
    std::vector<uint32_t>& counts = local_.local();
    for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
      const uint32_t c = CellOf(records + i * length, cube_);
      if (cells) cells[i] = c;
      ++counts[c];
    }
  });
}

std::vector<uint64_t> CellCounter::Counts() const {
  std::vector<uint64_t> counts(kCells, 0);
  for (const std::vector<uint32_t>& c : local_) {
    for (uint32_t u = 0; u < kCells; ++u) counts[u] += c[u];
  }
  return counts;
}

SpillRuns::SpillRuns(SpillFile* spill, size_t length, bool discard)
    : spill_(spill),
      length_(length),
      discard_(discard),
      buffer_(new uint8_t[kRunPoints * length]) {}

bool SpillRuns::Next(const uint8_t** records, size_t* first, size_t* count) {
  const uint64_t n = spill_->size() / length_;
  if (at_ >= n) return false;
  if (discard_ && at_ > 0) spill_->Discard(at_ * length_);
  *count = static_cast<size_t>(std::min<uint64_t>(kRunPoints, n - at_));
  spill_->Read(at_ * length_, *count * length_, buffer_.get());
  *records = buffer_.get();
  *first = static_cast<size_t>(at_);
  at_ += *count;
  return true;
}

std::vector<Bucket> ChooseBuckets(const std::vector<uint64_t>& cell_counts, size_t max_points,
                                  int max_level, std::vector<uint32_t>* bucket_of) {
  // Each level's counts, from the deepest up.
  std::array<std::vector<uint64_t>, kBucketLevel + 1> counts;
  counts[kBucketLevel] = cell_counts;
  for (int level = kBucketLevel - 1; level >= 0; --level) {
    counts[level].assign(size_t{1} << (3 * level), 0);
    for (size_t u = 0; u < counts[level + 1].size(); ++u) {
      counts[level][u >> 3] += counts[level + 1][u];
    }
  }
  std::vector<Bucket> buckets;
  auto cut = [&](auto&& self, int level, uint32_t code) -> void {
    const uint64_t c = counts[level][code];
    if (c == 0) return;
    if (level == max_level || c <= max_points) {
      buckets.push_back({level, code, 0, static_cast<size_t>(c)});
      return;
    }
    for (uint32_t o = 0; o < 8; ++o) self(self, level + 1, code << 3 | o);
  };
  cut(cut, 0, 0);
  bucket_of->assign(kCells, kNone);
  for (size_t j = 0; j < buckets.size(); ++j) {
    const int shift = 3 * (kBucketLevel - buckets[j].level);
    std::fill(bucket_of->begin() + (size_t{buckets[j].code} << shift),
              bucket_of->begin() + (size_t{buckets[j].code + 1} << shift),
              static_cast<uint32_t>(j));
  }
  return buckets;
}

void ListByBucket(const uint32_t* cells, size_t n, const std::vector<uint32_t>& bucket_of,
                  size_t first, size_t count, Bucket* buckets, uint32_t* list) {
  const size_t block = std::max(size_t{1} << 20, (n + 63) / 64);
  const size_t blocks = (n + block - 1) / block;
  std::vector<uint64_t> at(blocks * count, 0);
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    uint64_t* tally = at.data() + b * count;
    for (size_t i = b * block; i < std::min(n, (b + 1) * block); ++i) {
      ++tally[bucket_of[cells[i]] - first];
    }
  });
  size_t next = 0;
  for (size_t j = 0; j < count; ++j) {
    buckets[j].begin = next;
    for (size_t b = 0; b < blocks; ++b) {
      const uint64_t c = at[b * count + j];
      at[b * count + j] = next;
      next += c;
    }
    buckets[j].end = next;
  }
  CANDI_CHECK_EQ(next, n) << "COPC buckets";
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    uint64_t* to = at.data() + b * count;
    for (size_t i = b * block; i < std::min(n, (b + 1) * block); ++i) {
      list[to[bucket_of[cells[i]] - first]++] = static_cast<uint32_t>(i);
    }
  });
}

std::vector<GroupFiles> RouteToGroups(SpillFile* spill, size_t length, const Cube& cube,
                                      const std::vector<Bucket>& buckets,
                                      const std::vector<uint32_t>& bucket_of, size_t max_points,
                                      const std::string& dir) {
  std::vector<GroupFiles> groups;
  std::vector<uint32_t> group_of(buckets.size());
  for (size_t j = 0, points = 0; j < buckets.size(); ++j) {
    if (groups.empty() || (points + buckets[j].size() > max_points && points > 0)) {
      groups.emplace_back();
      groups.back().first = j;
      const std::string stem = dir + "/group-" + std::to_string(groups.size() - 1);
      groups.back().records = std::make_unique<SpillFile>(stem + ".records");
      groups.back().indices = std::make_unique<SpillRecords<uint32_t>>(stem + ".indices");
      points = 0;
    }
    ++groups.back().count;
    points += buckets[j].size();
    group_of[j] = static_cast<uint32_t>(groups.size() - 1);
  }
  // Runs of records: their groups found in parallel, then the records appended in order through
  // a buffer per group.
  constexpr size_t kBufferPoints = size_t{1} << 14;
  std::vector<std::vector<uint8_t>> record_buffer(groups.size());
  std::vector<std::vector<uint32_t>> index_buffer(groups.size());
  auto flush = [&](size_t g) {
    groups[g].records->Append(record_buffer[g].data(), record_buffer[g].size());
    groups[g].indices->Append(index_buffer[g].data(), index_buffer[g].size());
    record_buffer[g].clear();
    index_buffer[g].clear();
  };
  SpillRuns runs(spill, length, /*discard=*/true);
  const uint8_t* run;
  size_t first, m;
  std::vector<uint32_t> group;
  while (runs.Next(&run, &first, &m)) {
    group.resize(m);
    ParallelFor(size_t{0}, (m + kBlock - 1) / kBlock, [&](size_t b) {
      for (size_t i = b * kBlock; i < std::min(m, (b + 1) * kBlock); ++i) {
        group[i] = group_of[bucket_of[CellOf(run + i * length, cube)]];
      }
    });
    for (size_t i = 0; i < m; ++i) {
      const uint32_t g = group[i];
      const uint8_t* r = run + i * length;
      record_buffer[g].insert(record_buffer[g].end(), r, r + length);
      index_buffer[g].push_back(static_cast<uint32_t>(first + i));
      if (index_buffer[g].size() == kBufferPoints) flush(g);
    }
  }
  for (size_t g = 0; g < groups.size(); ++g) flush(g);
  return groups;
}

}  // namespace candi::io::copc_internal

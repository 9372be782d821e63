#include "io/copc/copc_write.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <tuple>

#include "core/binary_file.h"
#include "core/check.h"
#include "core/parallel.h"
#include "io/laz/laz_chunks.h"

namespace candi::io {

namespace {

constexpr size_t kCopcInfoBytes = 160;
constexpr size_t kEntryBytes = 32;

void PutF64(std::string* out, size_t at, double v) {
  StoreLE<double>(reinterpret_cast<uint8_t*>(out->data()) + at, v);
}
double GetF64(const std::string& in, size_t at) {
  return LoadLE<double>(reinterpret_cast<const uint8_t*>(in.data()) + at);
}

}  // namespace

std::string EncodeCopcInfo(const CopcInfo& info) {
  std::string out(kCopcInfoBytes, '\0');
  for (int k = 0; k < 3; ++k) PutF64(&out, 8 * k, info.center[k]);
  PutF64(&out, 24, info.halfsize);
  PutF64(&out, 32, info.spacing);
  uint8_t* p = reinterpret_cast<uint8_t*>(out.data());
  StoreLE<uint64_t>(p + 40, info.root_hier_offset);
  StoreLE<uint64_t>(p + 48, info.root_hier_size);
  PutF64(&out, 56, info.gpstime_minimum);
  PutF64(&out, 64, info.gpstime_maximum);
  return out;  // 72-159: reserved, zero
}

CopcInfo ParseCopcInfo(const std::string& data) {
  CANDI_CHECK_EQ(data.size(), kCopcInfoBytes) << "COPC info VLR";
  CopcInfo info;
  for (int k = 0; k < 3; ++k) info.center[k] = GetF64(data, 8 * k);
  info.halfsize = GetF64(data, 24);
  info.spacing = GetF64(data, 32);
  const uint8_t* p = reinterpret_cast<const uint8_t*>(data.data());
  info.root_hier_offset = LoadLE<uint64_t>(p + 40);
  info.root_hier_size = LoadLE<uint64_t>(p + 48);
  info.gpstime_minimum = GetF64(data, 56);
  info.gpstime_maximum = GetF64(data, 64);
  return info;
}

std::string EncodeCopcHierarchy(const std::vector<CopcEntry>& entries) {
  std::string out(entries.size() * kEntryBytes, '\0');
  uint8_t* p = reinterpret_cast<uint8_t*>(out.data());
  for (const CopcEntry& e : entries) {
    StoreLE<int32_t>(p, e.key.level);
    StoreLE<int32_t>(p + 4, e.key.x);
    StoreLE<int32_t>(p + 8, e.key.y);
    StoreLE<int32_t>(p + 12, e.key.z);
    StoreLE<uint64_t>(p + 16, e.offset);
    StoreLE<int32_t>(p + 24, e.bytes);
    StoreLE<int32_t>(p + 28, e.points);
    p += kEntryBytes;
  }
  return out;
}

std::vector<CopcEntry> ParseCopcHierarchy(const std::string& page) {
  CANDI_CHECK(page.size() % kEntryBytes == 0) << "COPC hierarchy page of " << page.size();
  std::vector<CopcEntry> entries(page.size() / kEntryBytes);
  const uint8_t* p = reinterpret_cast<const uint8_t*>(page.data());
  for (CopcEntry& e : entries) {
    e.key = {LoadLE<int32_t>(p), LoadLE<int32_t>(p + 4), LoadLE<int32_t>(p + 8),
             LoadLE<int32_t>(p + 12)};
    e.offset = LoadLE<uint64_t>(p + 16);
    e.bytes = LoadLE<int32_t>(p + 24);
    e.points = LoadLE<int32_t>(p + 28);
    p += kEntryBytes;
  }
  return entries;
}

namespace {

// The pages of one hierarchy, written depth first (untwine's CopcSupport::emitRoot).
class PageWriter {
 public:
  PageWriter(const CopcWriteOptions& options, const std::vector<CopcEntry>& entries,
             uint64_t payload_offset)
      : options_(options), entries_(entries), base_(payload_offset), children_(entries.size()),
        subtree_(entries.size(), 1) {}

  CopcHierarchy Write() {
    std::map<std::tuple<int, int, int, int>, size_t> index;
    for (size_t j = 0; j < entries_.size(); ++j) {
      const CopcKey& k = entries_[j].key;
      CANDI_CHECK(index.emplace(std::make_tuple(k.level, k.x, k.y, k.z), j).second)
          << "COPC node " << k.level << "-" << k.x << "-" << k.y << "-" << k.z << " twice";
    }
    std::vector<size_t> root;
    // Deepest first, so a node's subtree is counted before its parent adds it.
    for (auto it = index.rbegin(); it != index.rend(); ++it) {
      const auto [level, x, y, z] = it->first;
      if (level == 0) {
        root.push_back(it->second);
        continue;
      }
      const auto parent = index.find(std::make_tuple(level - 1, x / 2, y / 2, z / 2));
      CANDI_CHECK(parent != index.end())
          << "COPC node " << level << "-" << x << "-" << y << "-" << z << " without its parent";
      children_[parent->second].push_back(it->second);
      subtree_[parent->second] += subtree_[it->second];
    }
    CANDI_CHECK_EQ(root.size(), size_t{1}) << "COPC hierarchy roots";
    for (std::vector<size_t>& c : children_) {
      std::sort(c.begin(), c.end(), [&](size_t a, size_t b) { return Octant(a) < Octant(b); });
    }
    CopcHierarchy h;
    const CopcEntry top = EmitPage(root[0]);
    h.data = std::move(data_);
    h.root_offset = top.offset - base_;
    h.root_size = static_cast<uint64_t>(top.bytes);
    return h;
  }

 private:
  int Octant(size_t j) const {
    const CopcKey& k = entries_[j].key;
    return (k.x & 1) | (k.y & 1) << 1 | (k.z & 1) << 2;
  }

  // Writes the page of `root`'s subtree (its child pages first); its entry in the parent page.
  CopcEntry EmitPage(size_t root) {
    std::vector<CopcEntry> page{entries_[root]};
    EmitChildren(root, entries_[root].key.level + options_.page_levels, &page);
    const std::string bytes = EncodeCopcHierarchy(page);
    CANDI_CHECK(bytes.size() <= size_t{std::numeric_limits<int32_t>::max()})
        << "COPC hierarchy page of " << page.size() << " entries";
    const CopcEntry entry{entries_[root].key, base_ + data_.size(),
                          static_cast<int32_t>(bytes.size()), -1};
    data_ += bytes;
    return entry;
  }

  void EmitChildren(size_t parent, int stop_level, std::vector<CopcEntry>* page) {
    for (size_t c : children_[parent]) {
      if (entries_[c].key.level != stop_level || subtree_[c] <= options_.min_page_nodes) {
        page->push_back(entries_[c]);
        EmitChildren(c, stop_level, page);
      } else {
        page->push_back(EmitPage(c));
      }
    }
  }

  const CopcWriteOptions& options_;
  const std::vector<CopcEntry>& entries_;
  const uint64_t base_;
  std::vector<std::vector<size_t>> children_;
  std::vector<int64_t> subtree_;  // nodes in each node's subtree, itself included
  std::string data_;
};

}  // namespace

CopcHierarchy EncodeCopcHierarchyPages(const CopcWriteOptions& options,
                                       const std::vector<CopcEntry>& entries,
                                       uint64_t payload_offset) {
  options.Check();
  CANDI_CHECK(!entries.empty()) << "COPC hierarchy of no node";
  return PageWriter(options, entries, payload_offset).Write();
}

void ExtendCopcGpsTimeRange(const uint8_t* records, size_t n, size_t record_length,
                            size_t gps_offset, std::array<double, 2>* range) {
  constexpr size_t kBlock = size_t{1} << 20;
  const size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::array<double, 2>> block_range(blocks, {INFINITY, -INFINITY});
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
      const double t = LoadLE<double>(records + i * record_length + gps_offset);
      if (std::isnan(t)) continue;
      block_range[b][0] = std::min(block_range[b][0], t);
      block_range[b][1] = std::max(block_range[b][1], t);
    }
  });
  for (const std::array<double, 2>& r : block_range) {
    (*range)[0] = std::min((*range)[0], r[0]);
    (*range)[1] = std::max((*range)[1], r[1]);
  }
}

std::array<double, 2> CopcGpsTimes(const std::array<double, 2>& range) {
  if (!(range[0] <= range[1])) return {0.0, 0.0};  // no time, or none but NaN
  return range;
}

CopcPointData WriteCopcNodes(const CopcOctreeOptions& options, const CopcRecords& records,
                             const Eigen::Vector3d& scale, const Eigen::Vector3d& offset,
                             const CopcXyzBounds* xyz_bounds,
                             const laz::Vlr& vlr, uint64_t first_chunk,
                             const std::function<void(const uint8_t*, size_t)>& sink,
                             const std::function<void(uint64_t, uint64_t)>& bucketing,
                             const std::function<void(uint64_t, uint64_t)>& chunks) {
  CANDI_CHECK(vlr.compressor == laz::kLayeredChunked &&
              records.record_length == static_cast<size_t>(vlr.record_length()))
      << "COPC chunks are layered, with the record's items";
  CopcPointData data;
  std::vector<uint32_t> bytes, points;
  uint64_t offset_in_file = first_chunk;
  data.tree = BuildCopcNodes(
      options, records, scale, offset, xyz_bounds,
      [&vlr](const CopcKey&, const uint8_t* node_records, const uint32_t*, size_t count,
             std::vector<uint8_t>* out) {
        laz::EncodeLayeredChunk(vlr.items, node_records, static_cast<uint32_t>(count), out);
      },
      [&](const CopcKey& key, uint64_t count, std::vector<uint8_t>* chunk) {
        CANDI_CHECK(chunk->size() <= size_t{std::numeric_limits<int32_t>::max()} &&
                    count <= uint64_t{std::numeric_limits<int32_t>::max()})
            << "COPC node of " << count << " points, " << chunk->size() << " bytes";
        sink(chunk->data(), chunk->size());
        data.entries.push_back({key, offset_in_file, static_cast<int32_t>(chunk->size()),
                                static_cast<int32_t>(count)});
        bytes.push_back(static_cast<uint32_t>(chunk->size()));
        points.push_back(static_cast<uint32_t>(count));
        offset_in_file += chunk->size();
        std::vector<uint8_t>().swap(*chunk);  // written: its memory back
      },
      bucketing, chunks);
  // No point: the hierarchy is the root alone, of no point and no chunk (COPC allows a node of
  // point count 0), so the file is valid and reads as empty.
  if (data.entries.empty()) data.entries.push_back({CopcKey{}, 0, 0, 0});
  data.chunk_table = EncodeLazChunkTable(bytes, points);
  return data;
}

}  // namespace candi::io

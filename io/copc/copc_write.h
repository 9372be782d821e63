// COPC 1.0 (https://copc.io) records and point data: the "copc" info VLR (record 1, 160 bytes),
// the EPT hierarchy EVLR (record 1000, 32-byte entries), and the octree's nodes as one LAZ chunk
// each (layered, variable-size chunks, io/copc/copc_octree.h).
//
// Internal to the LAS writer (io/las/las_writer.cc), which writes a COPC file for a name ending in
// ".copc.laz": LAS 1.4, point format 6-8, the info VLR first, the laszip VLR with variable
// chunks, the point data (the chunk table's offset, the nodes' chunks bucket by bucket and the
// nodes above the buckets last, the chunk table with per-chunk point counts), then the hierarchy
// EVLR (its pages, the root page last) and the EVLRs kept from the source.
// Failure: the Parse* functions (for tests and tools) CANDI_CHECK the payload sizes; a chunk the
// encoder refuses is a CANDI_CHECK (the writer built the records). Thread-safety: pure
// functions; WriteCopcNodes compresses in parallel with the same bytes on any thread count.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "io/copc/copc_octree.h"
#include "io/laz/laz_format.h"
#include "io/point_file.h"

namespace candi::io {

inline constexpr const char* kCopcUserId = "copc";
inline constexpr uint16_t kCopcInfoRecord = 1;
inline constexpr uint16_t kCopcHierarchyRecord = 1000;

struct CopcInfo {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // of the octree's cube, world
  double halfsize = 0.0;                             // half the cube's width
  double spacing = 0.0;                              // root node's point spacing
  uint64_t root_hier_offset = 0;                     // file offset of the root hierarchy page
  uint64_t root_hier_size = 0;                       // its bytes
  double gpstime_minimum = 0.0, gpstime_maximum = 0.0;
};
std::string EncodeCopcInfo(const CopcInfo& info);  // 160 bytes, the reserved ones zero
CopcInfo ParseCopcInfo(const std::string& data);   // CANDI_CHECK: 160 bytes

struct CopcEntry {
  CopcKey key;
  uint64_t offset = 0;  // file offset of the node's chunk (of a child page when points = -1)
  int32_t bytes = 0;    // its size
  int32_t points = 0;   // points in the chunk; -1: a child hierarchy page
};
std::string EncodeCopcHierarchy(const std::vector<CopcEntry>& entries);  // 32 bytes an entry
std::vector<CopcEntry> ParseCopcHierarchy(const std::string& page);      // CANDI_CHECK: k * 32

// The hierarchy EVLR's payload: the pages of `entries` (one a node, each node's parent among
// them), cut as untwine and PDAL cut them (CopcWriteOptions, io/point_file.h): a page holds its
// root and the nodes page_levels below it in depth-first order, children by octant; a node at
// that depth whose subtree has more than min_page_nodes nodes gets a page of its own, and the
// parent page's entry for it holds the page's file offset, its bytes and point count -1. Child
// pages precede their parent's, so the root page is last. `payload_offset`: the file offset at
// which the payload will be written. CANDI_CHECK: a node without its parent, no root.
struct CopcHierarchy {
  std::string data;          // the pages
  uint64_t root_offset = 0;  // of the root page, from the payload's start
  uint64_t root_size = 0;    // its bytes
};
CopcHierarchy EncodeCopcHierarchyPages(const CopcWriteOptions& options,
                                       const std::vector<CopcEntry>& entries,
                                       uint64_t payload_offset);

struct CopcPointData {
  CopcOctree tree;                   // the cube; the nodes in the order of their chunks
  std::vector<CopcEntry> entries;    // one a node, in the order of their chunks
  std::vector<uint8_t> chunk_table;  // LASzip's, variable chunks
};
// Builds the octree of the records (in memory or spilled: io/copc/copc_octree.h's BuildCopcNodes) and compresses each node's records (in input order) into one chunk with the
// items of `vlr` (layered), handing the chunks to `sink` in the order the octree hands the nodes
// on; the first chunk starts at file offset `first_chunk`. The chunks are compressed on several
// threads, bucket by bucket, with the same bytes on any thread count. An exception from the sink
// ends the writing and is rethrown; no chunk is handed on after it. No record: the entries are
// the root alone, of 0 points, and no chunk.
// `bucketing`, `chunks` (may be null): (done, n) as the buckets are cut and as chunks are written.
CopcPointData WriteCopcNodes(const CopcOctreeOptions& options, const CopcRecords& records,
                             const Eigen::Vector3d& scale, const Eigen::Vector3d& offset,
                             const CopcXyzBounds* xyz_bounds,
                             const laz::Vlr& vlr, uint64_t first_chunk,
                             const std::function<void(const uint8_t*, size_t)>& sink,
                             const std::function<void(uint64_t, uint64_t)>& bucketing = {},
                             const std::function<void(uint64_t, uint64_t)>& chunks = {});

// The least and the greatest GPS time of n records (the double at byte gps_offset of each) and
// of *range, NaN times left out, by parallel blocks (no order matters): a writer extends it as
// the records come, from {inf, -inf}. CopcGpsTimes: the info VLR's range, {0, 0} when it holds
// no time.
void ExtendCopcGpsTimeRange(const uint8_t* records, size_t n, size_t record_length,
                            size_t gps_offset, std::array<double, 2>* range);
std::array<double, 2> CopcGpsTimes(const std::array<double, 2>& range);

}  // namespace candi::io

// The octree of a COPC file (https://copc.io, COPC 1.0): which points each node (voxel) holds.
//
// The cube: centred on the points' bounds, halfsize = half the largest extent (or the largest scale
// when every point is at one place). Node (d, x, y, z) is the cube's cell at level d, width 2 *
// halfsize / 2^d, x, y, z in [0, 2^d). Each node lays a grid of 128^3 cells over itself (untwine's
// CellCount) and keeps one point a cell: the one nearest to the cell's centre (squared distance
// rounded to float), the earlier in input order on a tie; the others go to the child octant holding
// them. So the points a node keeps are at most one per cell of width spacing / 2^d, spacing = 2 *
// halfsize / 128 being the root's (COPC info "spacing"; untwine and PDAL write the cube width over
// their cell count, 128). A node whose cells are narrower than the smallest LAS scale keeps all its
// points (only exact duplicates can share a cell there), so the depth is bounded. Small nodes are
// avoided as untwine avoids them (bu/Processor.cpp: MinimumPoints 100, MinimumTotalPoints 1500): a
// node reached by fewer than min_subtree_points points keeps them all, and a child octant that
// would get fewer than min_octant_points stays in its parent. (Each LAZ chunk costs its coder's
// set-up: a scan with far jumps made 9,000 nodes of ~6 points of 60,000 points without this.) A
// node's points in octants that have a child node are one a cell.
//
// Positions are the records' integer X, Y, Z (LAS units, world = X * scale + offset): a point
// belongs to the cell floor(t * 2^L) at level L, t = (world - cube min) / cube width, clamped to
// [0, 2^L - 1], the same rule at every level, so a point of node (d, x) lies in a child (d + 1, 2x
// or 2x + 1); each level's cell is a shift of floor(t * 2^62). Deterministic: the nodes and their
// points do not depend on the thread count.
// Built bucket by bucket (copc_nodes.cc): the cube's cells at level 7 are counted (the points'
// places, by parallel blocks), and the cube is cut into buckets, nodes of at most bucket_points
// points or at level 7 (fewer where cells narrower than a LAS unit start sooner), a bucket's
// points listed in input order. A bucket's points are then built alone, in Morton order in the
// cache (a node's points, its children's and each of its cells contiguous ranges of it, a cell's
// nearest point chosen from its run, a point's distance computed only where a bound from its
// Morton code does not rule it out, and flagged as kept in place): the levels above the bucket
// first, whose cells (7 levels below a node of level < 7) lie whole in it, then its own subtree,
// whose records are gathered in node order and encoded while the bucket is in the cache. The
// rules above the buckets need counts across them: a node above whose subtree or octant folds
// (fewer points reach it than the minimums below) can only hold buckets of which fewer than the
// larger minimum reach their parent's level; those are held, their nodes not handed on, until
// every bucket's counts are in. The nodes above the buckets are encoded last, their points
// gathered from the records in input order. A key holds 21 levels; nodes more than 14 levels
// below the level it was made for are keyed again from their own level. Memory: the records, 8
// bytes a point (each point's cell while the buckets are cut, then each bucket's list), 16 for
// each point of a node above the buckets, and each bucket in the works ~70 bytes a point (spilled
// records: CopcRecords). Deterministic: the nodes, their points and the order they are handed on
// do not depend on the thread count. Thread-safety: a pure function.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace candi {
class SpillFile;  // core/spill_file.h
}  // namespace candi

namespace candi::io {

inline constexpr int kCopcCellsPerAxis = 128;

struct CopcKey {
  int32_t level = 0, x = 0, y = 0, z = 0;
  bool operator==(const CopcKey& o) const {
    return level == o.level && x == o.x && y == o.y && z == o.z;
  }
};

struct CopcNode {
  CopcKey key;
  uint64_t size = 0;             // points it holds
  std::vector<uint64_t> points;  // their records' indices, ascending (BuildCopcOctree's only)
};

struct CopcOctree {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // world, metres (LAS units)
  double halfsize = 0.0;                             // half the cube's width
  double spacing = 0.0;                              // root cell width: 2 * halfsize / 128
  std::vector<CopcNode> nodes;                       // none empty
  // World bounds of a node's cube.
  Eigen::Vector3d NodeMin(const CopcKey& key) const;
  double NodeWidth(const CopcKey& key) const;
};

struct CopcOctreeOptions {
  // A node reached by fewer points keeps them all (no children). >= 0; 0: never.
  int min_subtree_points = 1500;
  // A child octant of fewer points is kept in its parent. >= 0; 0: never.
  int min_octant_points = 100;
  // The sort's scratch on each thread, in points (24 bytes each; 48 MiB): larger groups are
  // sorted in place, more slowly. 0: every group in place.
  size_t sort_scratch_points = size_t{1} << 21;
  // A node of more points than this is cut into buckets (down to level 7). >= 1. The tree is
  // the same for any value; the order the nodes are handed on is not.
  size_t bucket_points = size_t{1} << 17;
  // Buckets are built in parallel by batches of consecutive ones of about this many points
  // (scheduling only: the nodes and their order are the same for any value). >= 1.
  size_t batch_points = size_t{1} << 22;
  void Check() const;
};

using CopcXyzBounds = std::array<std::array<int32_t, 3>, 2>;

// What a node becomes (its LAZ chunk, for the COPC writer): called on several threads at once,
// once a node, with the node's `count` records (record_length bytes each, contiguous, in input
// order) and their indices among the n; appends to *out (empty when called).
using CopcNodeEncoder =
    std::function<void(const CopcKey& key, const uint8_t* records, const uint32_t* indices,
                       size_t count, std::vector<uint8_t>* out)>;
// Takes the nodes, one call at a time, in the order they are written: the buckets' nodes
// bucket by bucket (in Morton order), each bucket's level by level, then the nodes above the
// buckets level by level. An exception ends the build and reaches the caller.
using CopcNodeSink =
    std::function<void(const CopcKey& key, uint64_t count, std::vector<uint8_t>* encoded)>;

// The n records of a build (record_length bytes each, X, Y, Z int32 at bytes 0, 4, 8): in memory,
// or spilled to a file in input order, for a cloud larger than memory. A spilled build holds at
// most memory_points of them at a time (and each point kept above the buckets, 16 bytes): the
// buckets are cut from every cell's count (the spill read once, in order), then the records go
// to groups of consecutive buckets of at most memory_points points (files in spill_dir: about
// the spill's size again, whose blocks are given back as it is read), each group built as the
// records in memory are; the records of points above the buckets are copied to one more file.
// The nodes, their points and their order are those of the records in memory.
struct CopcRecords {
  const uint8_t* data = nullptr;  // in memory, or
  SpillFile* spill = nullptr;     // spilled (the build consumes it)
  size_t n = 0, record_length = 0;
  size_t memory_points = 0;  // spilled: > 0
  std::string spill_dir;     // spilled: a temporary folder for the build's own files
};

// Builds the octree of the records with the header's scale and offset, encodes each node and
// hands it to `sink`; returns the cube
// and the nodes (without their points lists) in the sink's order. `xyz_bounds` (may be null):
// the records' least and greatest X, Y, Z, when the caller has them (a writer tracks them),
// which saves a pass over the records; the tree is the same. `bucketing` and `encoding` (may be
// null): (done, n) as the buckets are cut (points placed) and as nodes are handed on (points
// settled). CANDI_CHECK: n < 2^32.
CopcOctree BuildCopcNodes(const CopcOctreeOptions& options, const CopcRecords& records,
                          const Eigen::Vector3d& scale, const Eigen::Vector3d& offset,
                          const CopcXyzBounds* xyz_bounds, const CopcNodeEncoder& encode,
                          const CopcNodeSink& sink,
                          const std::function<void(uint64_t, uint64_t)>& bucketing = {},
                          const std::function<void(uint64_t, uint64_t)>& encoding = {});
// The same, n records in memory.
CopcOctree BuildCopcNodes(const CopcOctreeOptions& options, const uint8_t* records, size_t n,
                          size_t record_length, const Eigen::Vector3d& scale,
                          const Eigen::Vector3d& offset, const CopcXyzBounds* xyz_bounds,
                          const CopcNodeEncoder& encode, const CopcNodeSink& sink,
                          const std::function<void(uint64_t, uint64_t)>& bucketing = {},
                          const std::function<void(uint64_t, uint64_t)>& encoding = {});

// The octree of n LAS records as BuildCopcNodes builds it, each node with its points list, the
// nodes level by level, each level ordered by (x, y, z).
CopcOctree BuildCopcOctree(const CopcOctreeOptions& options, const uint8_t* records, size_t n,
                           size_t record_length, const Eigen::Vector3d& scale,
                           const Eigen::Vector3d& offset,
                           const CopcXyzBounds* xyz_bounds = nullptr);
CopcOctree BuildCopcOctree(const CopcOctreeOptions& options, const CopcRecords& records,
                           const Eigen::Vector3d& scale, const Eigen::Vector3d& offset,
                           const CopcXyzBounds* xyz_bounds = nullptr);

}  // namespace candi::io

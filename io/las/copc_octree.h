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
// Built level by level over the points in Morton order (sorted once by a parallel radix pass
// on the first 12 bits and each bucket on its own): a node's points, its children's and each of
// its cells are then contiguous ranges, so a level is one pass over its nodes' ranges, a cell's
// nearest point chosen from its run (a point's distance computed only where a bound from its
// Morton code does not rule it out) and flagged as kept in place. A large node is split by several
// threads in blocks of whole cells; small nodes a thread each. A key holds 21 levels; nodes more
// than 14 levels below the level it was made for are keyed again from their own level.
// Memory: 32 bytes a point, or the record length if more (each point's key, X, Y, Z and index,
// its key again while sorting), and the node of each. Thread-safety: a pure function.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Core>

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
  std::vector<uint64_t> points;  // their records' indices, ascending (empty in a CopcPartition)
};

struct CopcOctree {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // world, metres (LAS units)
  double halfsize = 0.0;                             // half the cube's width
  double spacing = 0.0;                              // root cell width: 2 * halfsize / 128
  std::vector<CopcNode> nodes;  // level by level, each level ordered by (x, y, z); none empty
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
  void Check() const;
};

// The octree of n LAS records (record_length bytes each, X, Y, Z int32 at bytes 0, 4, 8) with
// the header's scale and offset, as node sizes and each record's node: node_of[i] is the index
// in tree.nodes of the node holding record i. `memory` is the builder's, handed on (its contents
// undefined) so that the records in node order (RecordsByNode, io/las/copc_write.h) take no new
// pages. CANDI_CHECK: n < 2^32.
struct CopcPartition {
  CopcOctree tree;                       // nodes without their points lists
  std::unique_ptr<uint32_t[]> node_of;   // n
  std::unique_ptr<uint8_t[]> memory;     // memory_bytes >= n * record_length
  size_t memory_bytes = 0;
};
// `progress` (may be null): (points whose node is settled, n) after each level. `xyz_bounds`
// (may be null): the records' least and greatest X, Y, Z, when the caller has them (a writer
// tracks them), which saves a pass over the records; the tree is the same.
using CopcXyzBounds = std::array<std::array<int32_t, 3>, 2>;
CopcPartition PartitionCopcOctree(const CopcOctreeOptions& options, const uint8_t* records,
                                  size_t n, size_t record_length, const Eigen::Vector3d& scale,
                                  const Eigen::Vector3d& offset,
                                  const std::function<void(uint64_t, uint64_t)>& progress = {},
                                  const CopcXyzBounds* xyz_bounds = nullptr);

// Builds the octree of n LAS records (record_length bytes each, X, Y, Z int32 at bytes 0, 4, 8)
// with the header's scale and offset.
CopcOctree BuildCopcOctree(const CopcOctreeOptions& options, const uint8_t* records, size_t n,
                           size_t record_length, const Eigen::Vector3d& scale,
                           const Eigen::Vector3d& offset);

}  // namespace candi::io

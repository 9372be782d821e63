// Internal to io/copc (copc_octree.cc, copc_nodes.cc): the machinery that builds the octree of
// io/copc/copc_octree.h over a range of points in Morton order (its places, keys, sort and the
// level-by-level builder), shared by the bucket pipeline that runs it bucket by bucket.
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "core/morton.h"
#include "io/copc/copc_octree.h"

namespace candi::io::copc_internal {

constexpr int kCellBits = 7;  // 128 = 2^7 cells a side
static_assert(1 << kCellBits == kCopcCellsPerAxis);

// A point's place in the cube, per axis q = floor(t * 2^62), t = (world - cube min) / cube width
// clamped to [0, 1): floor(t * 2^L) = q >> (62 - L) exactly for every level L <= 62 (t * 2^L is
// exact in binary floating point), so a cell is a shift, and the place in it the bits below.
constexpr int kFixedBits = 62;
using Place = std::array<uint64_t, 3>;

// floor(t * 2^62) clamped to [0, 2^62 - 1]; the conversion truncates, which is the floor for the
// positive values it sees (and needs no libm call on the baseline x86-64 this is built for).
inline uint64_t ToFixed(double t) {
  constexpr double kOne = static_cast<double>(uint64_t{1} << kFixedBits);
  const double u = t * kOne;
  if (!(u > 0.0)) return 0;
  return u >= kOne ? (uint64_t{1} << kFixedBits) - 1
                   : static_cast<uint64_t>(static_cast<int64_t>(u));
}

// The points are kept in Morton order: a key holds a point's octants at kKeyLevels levels below
// a base level (3 bits each, the nearer level higher), so that a node's points, its children's
// and each of its cells (kCellBits levels down) are contiguous ranges while the node is at most
// kKeyLevels - kCellBits levels below the base; deeper nodes re-key their points from their own
// level. The key's top bit flags a point that a node has kept.
constexpr int kKeyLevels = 21;
constexpr uint64_t kKept = uint64_t{1} << 63;

// A point as the tree is built: its key, its record's X, Y, Z and its index.
struct Element {
  uint64_t key;
  int32_t xyz[3];
  uint32_t index;
};
static_assert(sizeof(Element) == 24);

inline uint64_t Code(const Element& e) { return e.key & ~kKept; }

// The cube and the records' scale and offset: a record's X, Y, Z to its place.
struct Cube {
  Eigen::Vector3d scale, offset, min;
  double width = 0.0;
  Place operator()(const int32_t* xyz) const {
    Place q;
    for (int k = 0; k < 3; ++k) q[k] = ToFixed((xyz[k] * scale[k] + offset[k] - min[k]) / width);
    return q;
  }
};

// The Morton code of a place's cells at levels base + 1 .. base + kKeyLevels (octant bits x, y,
// z = bits 0, 1, 2, as ChildKey has them); levels past 62 read as 0.
inline uint64_t MortonCode(const Place& q, int base) {
  const int shift = kFixedBits - base - kKeyLevels;
  auto bits = [&](int k) { return shift >= 0 ? q[k] >> shift : q[k] << -shift; };
  return MortonCode21(bits(0), bits(1), bits(2));
}

// The cube of n records (into tree: center, halfsize, spacing): centred on their world bounds
// (from xyz_bounds when given, else a pass over the records by parallel blocks), halfsize half
// the largest extent, or the largest scale when every point is at one place.
Cube RecordsCube(const uint8_t* records, size_t n, size_t length, const Eigen::Vector3d& scale,
                 const Eigen::Vector3d& offset, const CopcXyzBounds* xyz_bounds, CopcOctree* tree);

// The sorts of one build: each thread's scratch, of at most `cap` elements, freed with it.
// Sorts a[0, n) by Code, bits [0, top) (the ones above equal), most significant 9 bits first.
class Sorter {
 public:
  explicit Sorter(size_t cap) : cap_(cap) {}
  void operator()(Element* a, size_t n, int top);

 private:
  const size_t cap_;
  tbb::enumerable_thread_specific<std::vector<Element>> scratch_;
};

constexpr size_t kBlock = size_t{1} << 16;  // points a task takes

// A node being built: its points are the elements [begin, end) not yet kept, `size` of them.
struct Range {
  CopcKey key;
  size_t begin = 0, end = 0, size = 0;
};

inline CopcKey ChildKey(const CopcKey& key, int octant) {
  return {key.level + 1, 2 * key.x + (octant & 1), 2 * key.y + ((octant >> 1) & 1),
          2 * key.z + ((octant >> 2) & 1)};
}

// Nodes of more points than this are split by several threads (in a parallel build).
constexpr size_t kLargeNodePoints = size_t{1} << 16;

// The tree's points (elements, in Morton order by the keys of level `base`, 0 at first): a node
// keeps the nearest point of each of its cells (a run of its range) and passes the others on, in
// place, to the children that are the ranges of its octants. node_of[e.index] is set to the id
// of the node that keeps e.
class Builder {
 public:
  Builder(const CopcOctreeOptions& options, const Cube& cube, Sorter* sort, Element* elements,
          uint32_t* node_of)
      : options_(options), cube_(cube), sort_(sort), elements_(elements), node_of_(node_of) {}

  int base() const { return base_; }

  // Re-keys the points of `ranges` (one level's nodes) by the keys of their own level.
  void Rebase(const std::vector<Range>& ranges, bool parallel);

  // Splits node `range` (id `id`) by the rules of copc_octree.h: its points one a cell, the rest
  // to its children (into children, octant order); returns how many it keeps. `parallel`: its
  // cells in blocks on several threads.
  size_t Split(const Range& range, uint32_t id, bool keep_all, bool parallel,
               std::vector<Range>* children);

  // The nearest point of each cell of node `range` kept (as id), whatever the node's size and
  // its octants' (no rule); returns how many points it passes on. Serial.
  size_t KeepNearestOfCells(const Range& range, uint32_t id);

  // Keeps every point of [begin, end) not yet kept.
  void KeepAll(size_t begin, size_t end, uint32_t id, bool parallel);

 private:
  // Keeps the nearest point of each cell in [begin, end) (whole cells); returns how many points
  // of each octant it passes on.
  std::array<size_t, 8> KeepNearest(size_t begin, size_t end, int level, int cell_shift,
                                    int octant_shift, uint32_t id);

  const CopcOctreeOptions& options_;
  const Cube cube_;
  Sorter* const sort_;
  Element* const elements_;
  uint32_t* const node_of_;
  int base_ = 0;
};

}  // namespace candi::io::copc_internal

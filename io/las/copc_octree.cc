#include "io/las/copc_octree.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>

#include "core/binary_file.h"
#include "core/check.h"
#include "core/parallel.h"

namespace candi::io {

namespace {

constexpr int kCellBits = 7;  // 128 = 2^7 cells a side
static_assert(1 << kCellBits == kCopcCellsPerAxis);

// A node's points are sorted into buckets by their cells at the next kBucketBits levels (512
// buckets, of 16^3 cells each), so that a bucket's cells are chosen in a small table, and the
// points a node passes on are its children's, each a contiguous range.
constexpr int kBucketBits = 3;
constexpr size_t kBuckets = size_t{1} << (3 * kBucketBits);
constexpr int kBucketCellBits = kCellBits - kBucketBits;
constexpr size_t kBucketCells = size_t{1} << (3 * kBucketCellBits);
// A 3-bit value's bits spread to bits 0, 3 and 6: a bucket is x's spread | y's << 1 | z's << 2,
// so its top three bits are the octant one level down (bit 0: x, 1: y, 2: z).
constexpr uint32_t kSpread[8] = {0, 1, 8, 9, 64, 65, 72, 73};
static_assert(kBucketBits == 3);
// Nodes of more points than this are sorted by several threads; smaller ones by one each.
constexpr size_t kLargeNodePoints = size_t{1} << 16;
constexpr size_t kBlock = size_t{1} << 16;  // points a task sorts into buckets

// A point's place in the cube, per axis q = floor(t * 2^62), t = (world - cube min) / cube width
// clamped to [0, 1): floor(t * 2^L) = q >> (62 - L) exactly for every level L <= 62 (t * 2^L is
// exact in binary floating point), so a cell is a shift, and the place in it the bits below.
constexpr int kFixedBits = 62;
using Place = std::array<uint64_t, 3>;

// floor(t * 2^62) clamped to [0, 2^62 - 1]; the conversion truncates, which is the floor for the
// positive values it sees (and needs no libm call on the baseline x86-64 this is built for).
uint64_t ToFixed(double t) {
  constexpr double kOne = static_cast<double>(uint64_t{1} << kFixedBits);
  const double u = t * kOne;
  if (!(u > 0.0)) return 0;
  return u >= kOne ? (uint64_t{1} << kFixedBits) - 1
                   : static_cast<uint64_t>(static_cast<int64_t>(u));
}

// A point as the tree is built: its record's X, Y, Z and its index.
struct Element {
  int32_t xyz[3];
  uint32_t index;
};

struct Cube {
  Eigen::Vector3d scale, offset, min;
  double width = 0.0;
  Place operator()(const Element& e) const {
    Place q;
    for (int k = 0; k < 3; ++k) q[k] = ToFixed((e.xyz[k] * scale[k] + offset[k] - min[k]) / width);
    return q;
  }
};

// The cube of the points (into tree) and their elements (into elements[0, n)). The bounds are
// reduced block by block in parallel: a minimum and a maximum do not depend on the order.
void CubeElements(const uint8_t* records, size_t n, size_t length, const Eigen::Vector3d& scale,
                  const Eigen::Vector3d& offset, CopcOctree* tree, Cube* cube,
                  Element* elements) {
  const size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<Eigen::Vector3d> block_lo(blocks), block_hi(blocks);
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
    for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
      Element& e = elements[i];
      Eigen::Vector3d w;
      for (int k = 0; k < 3; ++k) {
        e.xyz[k] = LoadLE<int32_t>(records + i * length + 4 * k);
        w[k] = e.xyz[k] * scale[k] + offset[k];
      }
      e.index = static_cast<uint32_t>(i);
      lo = lo.cwiseMin(w);
      hi = hi.cwiseMax(w);
    }
    block_lo[b] = lo;
    block_hi[b] = hi;
  });
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (size_t b = 0; b < blocks; ++b) {
    lo = lo.cwiseMin(block_lo[b]);
    hi = hi.cwiseMax(block_hi[b]);
  }
  if (n == 0) lo = hi = Eigen::Vector3d::Zero();
  tree->center = 0.5 * (lo + hi);
  tree->halfsize = 0.5 * (hi - lo).maxCoeff();
  if (!(tree->halfsize > 0.0)) tree->halfsize = scale.cwiseAbs().maxCoeff();
  tree->spacing = 2.0 * tree->halfsize / kCopcCellsPerAxis;
  *cube = {scale, offset, tree->center.array() - tree->halfsize, 2.0 * tree->halfsize};
}

// Squared distance (float bits, which order as the values do for >= 0) above the index: the
// smaller of two is the nearer point, the earlier on a tie.
uint64_t Packed(double distance, uint32_t index) {
  const float d = static_cast<float>(distance);
  uint32_t bits;
  std::memcpy(&bits, &d, 4);
  return uint64_t{bits} << 32 | index;
}

constexpr uint64_t kEmpty = ~uint64_t{0};

// Runs f(0..n-1) on several threads or on this one.
template <typename F>
void Loop(bool parallel, size_t n, const F& f) {
  if (parallel) {
    ParallelFor(size_t{0}, n, f);
  } else {
    for (size_t i = 0; i < n; ++i) f(i);
  }
}

// A node being built: its points are elements [begin, end) of the level's buffer.
struct Range {
  CopcKey key;
  size_t begin = 0, end = 0;
};

CopcKey ChildKey(const CopcKey& key, int octant) {
  return {key.level + 1, 2 * key.x + (octant & 1), 2 * key.y + ((octant >> 1) & 1),
          2 * key.z + ((octant >> 2) & 1)};
}

// Bytes of the builder's buffers for n points.
size_t BuilderBytes(size_t n) { return n * (2 * sizeof(Element) + sizeof(uint16_t)); }

// The tree's buffers (in `memory`, BuilderBytes): a level's nodes are ranges of `points`; a node
// sorts its range into `sorted` by bucket and passes its children's points back into the front
// of its range. Pages are first touched by the passes that fill them, in parallel.
class Builder {
 public:
  Builder(const CopcOctreeOptions& options, const Cube& cube, size_t n, uint8_t* memory,
          uint32_t* node_of)
      : options_(options), cube_(cube), points_(reinterpret_cast<Element*>(memory)),
        sorted_(points_ + n), flags_(reinterpret_cast<uint16_t*>(sorted_ + n)),
        node_of_(node_of) {}

  // Splits node `range` (id `id`): its points one a cell, the rest to its children's ranges
  // (into children, octant order); its points' node_of set to id; returns how many it keeps.
  size_t Split(const Range& range, uint32_t id, bool keep_all, bool parallel,
               std::vector<Range>* children) {
    const size_t n = range.end - range.begin;
    if (keep_all || n < static_cast<size_t>(options_.min_subtree_points)) {
      Loop(parallel, n, [&](size_t i) { node_of_[points_[range.begin + i].index] = id; });
      return n;
    }
    const std::vector<size_t> bucket_begin = SortByBucket(range, parallel);
    const std::vector<size_t> passed = KeepNearest(range, bucket_begin, parallel);
    return PassOn(range, id, bucket_begin, passed, parallel, children);
  }

 private:
  // Sorts the range's points into `sorted` by bucket, block by block: each block's count of
  // each bucket, then its points to their places, in order. Returns where each bucket begins
  // (and, last, the range's end).
  std::vector<size_t> SortByBucket(const Range& range, bool parallel) {
    const size_t n = range.end - range.begin;
    const int level = range.key.level;
    const size_t blocks = (n + kBlock - 1) / kBlock;
    std::vector<uint32_t> counts(blocks * kBuckets, 0);
    const int bucket_shift = kFixedBits - (level + kBucketBits);
    auto block_begin = [&](size_t b) { return range.begin + b * kBlock; };
    auto block_end = [&](size_t b) { return std::min(range.end, range.begin + (b + 1) * kBlock); };
    Loop(parallel, blocks, [&](size_t b) {
      uint32_t* count = counts.data() + b * kBuckets;
      for (size_t i = block_begin(b); i < block_end(b); ++i) {
        const Place q = cube_(points_[i]);
        uint32_t bucket = 0;
        for (int k = 0; k < 3; ++k) bucket |= kSpread[(q[k] >> bucket_shift) & 7] << k;
        flags_[i] = static_cast<uint16_t>(bucket);
        ++count[bucket];
      }
    });
    std::vector<size_t> bucket_begin(kBuckets + 1);
    {
      size_t at = range.begin;
      for (size_t u = 0; u < kBuckets; ++u) {
        bucket_begin[u] = at;
        for (size_t b = 0; b < blocks; ++b) {
          const uint32_t c = counts[b * kBuckets + u];
          counts[b * kBuckets + u] = static_cast<uint32_t>(at - range.begin);
          at += c;
        }
      }
      bucket_begin[kBuckets] = at;
    }
    Loop(parallel, blocks, [&](size_t b) {
      uint32_t* next = counts.data() + b * kBuckets;
      for (size_t i = block_begin(b); i < block_end(b); ++i) {
        sorted_[range.begin + next[flags_[i]]++] = points_[i];
      }
    });
    return bucket_begin;
  }

  // Flags the point of each cell with the least packed (distance, index): it stays. Returns how
  // many points each bucket passes on.
  std::vector<size_t> KeepNearest(const Range& range, const std::vector<size_t>& bucket_begin,
                                  bool parallel) {
    const int level = range.key.level;
    const int cell_shift = kFixedBits - (level + kCellBits);
    const uint64_t frac_mask = (uint64_t{1} << cell_shift) - 1;
    const double frac_unit = std::ldexp(1.0, -cell_shift);
    std::vector<size_t> passed(kBuckets);  // points a bucket passes on
    Loop(parallel, kBuckets, [&](size_t u) {
      thread_local std::vector<uint64_t> best(kBucketCells, kEmpty);
      thread_local std::vector<uint64_t> packed;
      thread_local std::vector<uint16_t> cell;
      const size_t b = bucket_begin[u], m = bucket_begin[u + 1] - b;
      packed.resize(m);
      cell.resize(m);
      for (size_t i = 0; i < m; ++i) {
        const Place q = cube_(sorted_[b + i]);
        uint32_t c = 0;
        double distance = 0.0;
        for (int k = 0; k < 3; ++k) {
          const uint64_t local = (q[k] >> cell_shift) & ((uint64_t{1} << kBucketCellBits) - 1);
          c |= static_cast<uint32_t>(local) << (kBucketCellBits * k);
          const double e = static_cast<double>(q[k] & frac_mask) * frac_unit - 0.5;
          distance += e * e;
        }
        cell[i] = static_cast<uint16_t>(c);
        packed[i] = Packed(distance, sorted_[b + i].index);
        best[c] = std::min(best[c], packed[i]);
      }
      size_t pass = 0;
      for (size_t i = 0; i < m; ++i) {
        const bool keep = best[cell[i]] == packed[i];
        flags_[b + i] = keep;
        pass += !keep;
      }
      for (size_t i = 0; i < m; ++i) best[cell[i]] = kEmpty;
      passed[u] = pass;
    });
    return passed;
  }

  // The node keeps its flagged points and those of child octants of too few points; the others
  // go back to the front of the range, octant by octant, as the children's ranges. Returns how
  // many the node keeps.
  size_t PassOn(const Range& range, uint32_t id, const std::vector<size_t>& bucket_begin,
                const std::vector<size_t>& passed, bool parallel, std::vector<Range>* children) {
    const size_t n = range.end - range.begin;
    constexpr size_t kPerOctant = kBuckets / 8;
    std::array<size_t, 8> octant_size{};
    for (size_t u = 0; u < kBuckets; ++u) octant_size[u / kPerOctant] += passed[u];
    std::array<bool, 8> stays{};
    for (int o = 0; o < 8; ++o) {
      stays[o] = octant_size[o] < static_cast<size_t>(options_.min_octant_points);
    }
    std::vector<size_t> out(kBuckets);
    size_t at = range.begin, kept = n;
    for (size_t u = 0; u < kBuckets; ++u) {
      const int o = static_cast<int>(u / kPerOctant);
      if (u % kPerOctant == 0 && !stays[o] && octant_size[o] > 0) {
        children->push_back({ChildKey(range.key, o), at, at + octant_size[o]});
        kept -= octant_size[o];
      }
      out[u] = at;
      if (!stays[o]) at += passed[u];
    }
    Loop(parallel, kBuckets, [&](size_t u) {
      const bool stay = stays[u / kPerOctant];
      size_t to = out[u];
      for (size_t i = bucket_begin[u]; i < bucket_begin[u + 1]; ++i) {
        if (flags_[i] || stay) {
          node_of_[sorted_[i].index] = id;
        } else {
          points_[to++] = sorted_[i];
        }
      }
    });
    return kept;
  }

  const CopcOctreeOptions& options_;
  const Cube cube_;
  Element* const points_;
  Element* const sorted_;
  uint16_t* const flags_;  // a point's bucket while sorting, then whether it stays
  uint32_t* const node_of_;
};

}  // namespace

Eigen::Vector3d CopcOctree::NodeMin(const CopcKey& key) const {
  const double w = NodeWidth(key);
  return (center.array() - halfsize).matrix() + w * Eigen::Vector3d(key.x, key.y, key.z);
}

double CopcOctree::NodeWidth(const CopcKey& key) const {
  return std::ldexp(2.0 * halfsize, -key.level);
}

void CopcOctreeOptions::Check() const {
  if (min_subtree_points < 0) {
    throw std::invalid_argument("CopcOctreeOptions::min_subtree_points = " +
                                std::to_string(min_subtree_points) + "; must be >= 0");
  }
  if (min_octant_points < 0) {
    throw std::invalid_argument("CopcOctreeOptions::min_octant_points = " +
                                std::to_string(min_octant_points) + "; must be >= 0");
  }
}

CopcPartition PartitionCopcOctree(const CopcOctreeOptions& options, const uint8_t* records,
                                  size_t n, size_t record_length, const Eigen::Vector3d& scale,
                                  const Eigen::Vector3d& offset,
                                  const std::function<void(uint64_t, uint64_t)>& progress) {
  options.Check();
  CANDI_CHECK(n <= size_t{std::numeric_limits<uint32_t>::max()})
      << "a COPC octree of " << n << " points (at most 2^32 - 1)";
  CopcPartition partition;
  CopcOctree& tree = partition.tree;
  // Not value-initialised: the passes write every byte they read.
  partition.memory_bytes = std::max(BuilderBytes(n), n * record_length);
  partition.memory.reset(new uint8_t[partition.memory_bytes]);
  static_assert(alignof(Element) <= alignof(std::max_align_t));
  Cube cube;
  CubeElements(records, n, record_length, scale, offset, &tree, &cube,
               reinterpret_cast<Element*>(partition.memory.get()));
  if (n == 0) return partition;
  partition.node_of.reset(new uint32_t[n]);
  Builder builder(options, cube, n, partition.memory.get(), partition.node_of.get());
  const double min_scale = scale.cwiseAbs().minCoeff();
  std::vector<Range> level{{CopcKey{}, 0, n}};
  uint64_t settled = 0;
  if (progress) progress(0, n);
  while (!level.empty()) {
    // Cells narrower than a LAS unit: only duplicates share one; keep them all here.
    const double cell = std::ldexp(tree.spacing, -level[0].key.level);
    const bool keep_all = cell < min_scale || level[0].key.level + kCellBits >= 62;
    const size_t first = tree.nodes.size();
    CANDI_CHECK(first + level.size() <= size_t{std::numeric_limits<uint32_t>::max()})
        << "COPC octree of " << first + level.size() << " nodes";
    for (const Range& r : level) tree.nodes.push_back({r.key, 0, {}});
    // Large nodes one at a time, each on every thread; the small ones a thread each.
    std::vector<std::vector<Range>> children(level.size());
    std::vector<size_t> small;
    for (size_t j = 0; j < level.size(); ++j) {
      if (level[j].end - level[j].begin > kLargeNodePoints) {
        tree.nodes[first + j].size = builder.Split(level[j], static_cast<uint32_t>(first + j),
                                                   keep_all, true, &children[j]);
      } else {
        small.push_back(j);
      }
    }
    ParallelFor(size_t{0}, small.size(), [&](size_t s) {
      const size_t j = small[s];
      tree.nodes[first + j].size = builder.Split(level[j], static_cast<uint32_t>(first + j),
                                                 keep_all, false, &children[j]);
    });
    for (size_t j = first; j < tree.nodes.size(); ++j) settled += tree.nodes[j].size;
    if (progress) progress(settled, n);
    std::vector<Range> next;
    for (const std::vector<Range>& c : children) next.insert(next.end(), c.begin(), c.end());
    std::sort(next.begin(), next.end(), [](const Range& a, const Range& b) {
      return std::tie(a.key.x, a.key.y, a.key.z) < std::tie(b.key.x, b.key.y, b.key.z);
    });
    level = std::move(next);
  }
  return partition;
}

CopcOctree BuildCopcOctree(const CopcOctreeOptions& options, const uint8_t* records, size_t n,
                           size_t record_length, const Eigen::Vector3d& scale,
                           const Eigen::Vector3d& offset) {
  CopcPartition partition = PartitionCopcOctree(options, records, n, record_length, scale, offset);
  std::vector<CopcNode>& nodes = partition.tree.nodes;
  for (CopcNode& node : nodes) node.points.reserve(node.size);
  for (size_t i = 0; i < n; ++i) nodes[partition.node_of[i]].points.push_back(i);
  return std::move(partition.tree);
}

}  // namespace candi::io

#include "io/las/copc_octree.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <memory>
#include <mutex>
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

struct Split {
  std::vector<uint64_t> kept;
  std::array<std::vector<uint64_t>, 8> children;  // octant bit 0: x, 1: y, 2: z
};

// Nodes of more points than this are split through a table of every cell (O(n), parallel);
// smaller ones sort their (cell, position) keys.
constexpr size_t kLargeNodePoints = size_t{1} << 16;
constexpr uint32_t kNone = 0xFFFFFFFFu;

// A point's place in the cube, per axis q = floor(t * 2^62), t = (world - cube min) / cube width
// clamped to [0, 1): floor(t * 2^L) = q >> (62 - L) exactly for every level L <= 62 (t * 2^L is
// exact in binary floating point), so a cell is a shift, and the place in it the bits below.
constexpr int kFixedBits = 62;
using Place = std::array<uint64_t, 3>;

uint64_t ToFixed(double t) {
  constexpr double kOne = static_cast<double>(uint64_t{1} << kFixedBits);
  const double u = std::floor(t * kOne);
  if (!(u > 0.0)) return 0;
  return u >= kOne ? (uint64_t{1} << kFixedBits) - 1 : static_cast<uint64_t>(u);
}

Eigen::Vector3d World(const uint8_t* p, const Eigen::Vector3d& scale, const Eigen::Vector3d& offset) {
  Eigen::Vector3d w;
  for (int k = 0; k < 3; ++k) w[k] = LoadLE<int32_t>(p + 4 * k) * scale[k] + offset[k];
  return w;
}

// The cube of the points (into tree) and their places in it. The bounds are reduced block by
// block in parallel: a minimum and a maximum do not depend on the order.
std::vector<Place> CubePlaces(const uint8_t* records, size_t n, size_t length,
                              const Eigen::Vector3d& scale, const Eigen::Vector3d& offset,
                              CopcOctree* tree) {
  constexpr size_t kBlock = size_t{1} << 16;
  const size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<Eigen::Vector3d> block_lo(blocks), block_hi(blocks);
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
    for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
      const Eigen::Vector3d w = World(records + i * length, scale, offset);
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
  const Eigen::Vector3d min = tree->center.array() - tree->halfsize;
  const double width = 2.0 * tree->halfsize;
  std::vector<Place> places(n);
  ParallelFor(size_t{0}, n, [&](size_t i) {
    const Eigen::Vector3d t = (World(records + i * length, scale, offset) - min) / width;
    for (int k = 0; k < 3; ++k) places[i][k] = ToFixed(t[k]);
  });
  return places;
}

// A point in a node: its cell (21 bits: x, y, z of 7), the child octant holding it (bit 0: x,
// 1: y, 2: z) and its squared distance to the cell's centre in cell widths.
struct Located {
  uint64_t cell = 0;
  uint32_t octant = 0;
  double distance = 0.0;
};

// Squared distance (float bits, which order as the values do for >= 0) above the position: the
// smaller of two is the nearer point, the earlier on a tie.
uint64_t Packed(double distance, size_t j) {
  const float d = static_cast<float>(distance);
  uint32_t bits;
  std::memcpy(&bits, &d, 4);
  return uint64_t{bits} << 32 | j;
}

constexpr uint64_t kEmpty = ~uint64_t{0};
constexpr size_t kCells = size_t{1} << (3 * kCellBits);
using CellTable = std::unique_ptr<std::atomic<uint64_t>[]>;

// Tables of one slot a cell (16 MiB) for large nodes, every slot kEmpty between uses (a node
// empties the slots it used), so a table is filled once however many nodes use it.
class CellTables {
 public:
  CellTable Take() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (!free_.empty()) {
        CellTable t = std::move(free_.back());
        free_.pop_back();
        return t;
      }
    }
    CellTable t(new std::atomic<uint64_t>[kCells]);
    for (size_t c = 0; c < kCells; ++c) t[c].store(kEmpty, std::memory_order_relaxed);
    return t;
  }
  void Give(CellTable t) {
    const std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(t));
  }

 private:
  std::mutex mutex_;
  std::vector<CellTable> free_;
};

// Marks in `kept` the point of each cell with the least packed (distance, position), through a
// table's atomic minima, which do not depend on the order the threads reach them in.
template <typename Locate>
void KeepNearestLarge(size_t n, const Locate& locate, CellTables* tables,
                      std::vector<uint8_t>* octant, std::vector<uint8_t>* kept) {
  CellTable best = tables->Take();
  std::vector<uint32_t> cell(n);
  ParallelFor(size_t{0}, n, [&](size_t j) {
    const Located l = locate(j);
    (*octant)[j] = static_cast<uint8_t>(l.octant);
    cell[j] = static_cast<uint32_t>(l.cell);
    const uint64_t v = Packed(l.distance, j);
    std::atomic<uint64_t>& b = best[l.cell];
    uint64_t now = b.load(std::memory_order_relaxed);
    while (v < now && !b.compare_exchange_weak(now, v, std::memory_order_relaxed)) {
    }
  });
  ParallelFor(size_t{0}, n, [&](size_t j) {
    (*kept)[j] = (best[cell[j]].load(std::memory_order_relaxed) & 0xFFFFFFFFu) == j;
  });
  ParallelFor(size_t{0}, n,
              [&](size_t j) { best[cell[j]].store(kEmpty, std::memory_order_relaxed); });
  tables->Give(std::move(best));
}

// One node: one point a cell kept, the others to their child octants.
Split SplitNode(const CopcOctreeOptions& options, const CopcKey& key,
                const std::vector<uint64_t>& points, const std::vector<Place>& places,
                bool keep_all, CellTables* tables) {
  Split s;
  if (keep_all || points.size() < static_cast<size_t>(options.min_subtree_points)) {
    s.kept = points;
    return s;
  }
  const int shift = kFixedBits - (key.level + kCellBits);
  const uint64_t frac_mask = (uint64_t{1} << shift) - 1;
  const double frac_unit = std::ldexp(1.0, -shift);
  const uint64_t base[3] = {uint64_t(key.x) << kCellBits, uint64_t(key.y) << kCellBits,
                            uint64_t(key.z) << kCellBits};
  auto locate = [&](size_t j) {
    Located l;
    const Place& q = places[points[j]];
    for (int k = 0; k < 3; ++k) {
      const uint64_t local = (q[k] >> shift) - base[k];  // in [0, 128)
      l.cell = l.cell << kCellBits | local;
      l.octant |= static_cast<uint32_t>(local >> (kCellBits - 1)) << k;
      const double e = static_cast<double>(q[k] & frac_mask) * frac_unit - 0.5;
      l.distance += e * e;
    }
    return l;
  };
  const size_t n = points.size();
  CANDI_CHECK(n < kNone) << "COPC node of " << n << " points";
  std::vector<uint8_t> octant(n), kept(n, 0);
  if (n > kLargeNodePoints) {
    KeepNearestLarge(n, locate, tables, &octant, &kept);
  } else {
    // Per point: its cell above its position in the node, sorted; each cell's run's least packed.
    std::vector<uint64_t> keys(n), packed(n);
    for (size_t j = 0; j < n; ++j) {
      const Located l = locate(j);
      keys[j] = l.cell << 32 | j;
      packed[j] = Packed(l.distance, j);
      octant[j] = static_cast<uint8_t>(l.octant);
    }
    std::sort(keys.begin(), keys.end());
    for (size_t e = 0; e < n;) {
      const uint64_t cell = keys[e] >> 32;
      uint64_t best = packed[keys[e] & 0xFFFFFFFFu];
      for (++e; e < n && keys[e] >> 32 == cell; ++e) best = std::min(best, packed[keys[e] & 0xFFFFFFFFu]);
      kept[best & 0xFFFFFFFFu] = 1;
    }
  }
  std::array<size_t, 8> sizes{};
  for (size_t j = 0; j < n; ++j) sizes[octant[j]] += !kept[j];
  size_t kept_size = n;  // each list allocated once, at its size
  for (int o = 0; o < 8; ++o) {
    if (sizes[o] < static_cast<size_t>(options.min_octant_points)) continue;
    s.children[o].reserve(sizes[o]);
    kept_size -= sizes[o];
  }
  s.kept.reserve(kept_size);
  for (size_t j = 0; j < n; ++j) {
    const bool small = sizes[octant[j]] < static_cast<size_t>(options.min_octant_points);
    (kept[j] || small ? s.kept : s.children[octant[j]]).push_back(points[j]);
  }
  return s;
}

CopcKey ChildKey(const CopcKey& key, int octant) {
  return {key.level + 1, 2 * key.x + (octant & 1), 2 * key.y + ((octant >> 1) & 1),
          2 * key.z + ((octant >> 2) & 1)};
}

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

CopcOctree BuildCopcOctree(const CopcOctreeOptions& options, const uint8_t* records, size_t n,
                           size_t record_length, const Eigen::Vector3d& scale,
                           const Eigen::Vector3d& offset) {
  options.Check();
  CopcOctree tree;
  const std::vector<Place> places = CubePlaces(records, n, record_length, scale, offset, &tree);
  if (n == 0) return tree;
  const double min_scale = scale.cwiseAbs().minCoeff();
  CellTables tables;
  std::vector<CopcNode> level(1);
  level[0].points.resize(n);
  for (size_t i = 0; i < n; ++i) level[0].points[i] = i;
  while (!level.empty()) {
    // Cells narrower than a LAS unit: only duplicates share one; keep them all here.
    const double cell = std::ldexp(tree.spacing, -level[0].key.level);
    const bool keep_all = cell < min_scale || level[0].key.level + kCellBits >= 62;
    std::vector<Split> splits(level.size());
    ParallelFor(size_t{0}, level.size(), [&](size_t j) {
      splits[j] = SplitNode(options, level[j].key, level[j].points, places, keep_all, &tables);
    });
    std::vector<CopcNode> next;
    for (size_t j = 0; j < level.size(); ++j) {
      tree.nodes.push_back({level[j].key, std::move(splits[j].kept)});
      for (int o = 0; o < 8; ++o) {
        if (splits[j].children[o].empty()) continue;
        next.push_back({ChildKey(level[j].key, o), std::move(splits[j].children[o])});
      }
    }
    std::sort(next.begin(), next.end(), [](const CopcNode& a, const CopcNode& b) {
      return std::tie(a.key.x, a.key.y, a.key.z) < std::tie(b.key.x, b.key.y, b.key.z);
    });
    level = std::move(next);
  }
  return tree;
}

}  // namespace candi::io

#include "io/las/copc_octree.h"

#include <algorithm>
#include <cmath>
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

// Nodes of more points than this are split through a table of every cell (O(n), parallel cell
// location); smaller ones sort their (cell, position) keys.
constexpr size_t kLargeNodePoints = size_t{1} << 16;
constexpr uint32_t kNone = 0xFFFFFFFFu;

// The cube's positions of the points: (world - cube min) / cube width, in [0, 1].
std::vector<Eigen::Vector3d> CubePositions(const uint8_t* records, size_t n, size_t length,
                                           const Eigen::Vector3d& scale,
                                           const Eigen::Vector3d& offset, CopcOctree* tree) {
  std::vector<Eigen::Vector3d> world(n);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* p = records + i * length;
    for (int k = 0; k < 3; ++k) world[i][k] = LoadLE<int32_t>(p + 4 * k) * scale[k] + offset[k];
    lo = lo.cwiseMin(world[i]);
    hi = hi.cwiseMax(world[i]);
  }
  if (n == 0) lo = hi = Eigen::Vector3d::Zero();
  tree->center = 0.5 * (lo + hi);
  tree->halfsize = 0.5 * (hi - lo).maxCoeff();
  if (!(tree->halfsize > 0.0)) tree->halfsize = scale.cwiseAbs().maxCoeff();
  tree->spacing = 2.0 * tree->halfsize / kCopcCellsPerAxis;
  const Eigen::Vector3d min = tree->center.array() - tree->halfsize;
  const double width = 2.0 * tree->halfsize;
  ParallelFor(size_t{0}, n, [&](size_t i) { world[i] = (world[i] - min) / width; });
  return world;
}

// One node: one point a cell kept, the others to their child octants.
Split SplitNode(const CopcOctreeOptions& options, const CopcKey& key,
                const std::vector<uint64_t>& points, const std::vector<Eigen::Vector3d>& t,
                bool keep_all) {
  Split s;
  if (keep_all || points.size() < static_cast<size_t>(options.min_subtree_points)) {
    s.kept = points;
    return s;
  }
  const int level = key.level + kCellBits;
  const double factor = std::ldexp(1.0, level);
  const int64_t last = (int64_t{1} << level) - 1;
  const int64_t base[3] = {int64_t{key.x} << kCellBits, int64_t{key.y} << kCellBits,
                           int64_t{key.z} << kCellBits};
  // Per point: its cell (21 bits) above its position in the node (32 bits), its squared distance
  // to the cell's centre in cells, its child octant.
  const size_t n = points.size();
  CANDI_CHECK(n < kNone) << "COPC node of " << n << " points";
  std::vector<uint64_t> keys(n);
  std::vector<double> distance(n);
  std::vector<uint8_t> octant(n);
  auto locate = [&](size_t j) {
    uint64_t cell = 0;
    uint32_t oct = 0;
    double d = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double u = t[points[j]][k] * factor;
      const int64_t g = std::clamp(static_cast<int64_t>(std::floor(u)), int64_t{0}, last);
      const int64_t local = g - base[k];  // in [0, 128)
      cell = cell << kCellBits | static_cast<uint64_t>(local);
      oct |= static_cast<uint32_t>(local >> (kCellBits - 1)) << k;
      const double e = u - static_cast<double>(g) - 0.5;
      d += e * e;
    }
    keys[j] = cell << 32 | j;
    distance[j] = d;
    octant[j] = static_cast<uint8_t>(oct);
  };
  std::vector<uint8_t> kept(n, 0);
  if (n > kLargeNodePoints) {
    // One slot a cell (8 MiB): the best point so far, scanning in input order.
    ParallelFor(size_t{0}, n, locate);
    std::vector<uint32_t> best(size_t{1} << (3 * kCellBits), kNone);
    for (size_t j = 0; j < n; ++j) {
      uint32_t& b = best[keys[j] >> 32];
      if (b == kNone || distance[j] < distance[b]) b = static_cast<uint32_t>(j);
    }
    for (uint32_t b : best) {
      if (b != kNone) kept[b] = 1;
    }
  } else {
    for (size_t j = 0; j < n; ++j) locate(j);
    std::sort(keys.begin(), keys.end());
    // In each cell's run (positions ascending), the nearest to the centre, the first on a tie.
    for (size_t e = 0; e < n;) {
      const uint64_t cell = keys[e] >> 32;
      size_t best = keys[e] & 0xFFFFFFFFu;
      for (++e; e < n && keys[e] >> 32 == cell; ++e) {
        const size_t j = keys[e] & 0xFFFFFFFFu;
        if (distance[j] < distance[best]) best = j;
      }
      kept[best] = 1;
    }
  }
  std::array<size_t, 8> sizes{};
  for (size_t j = 0; j < n; ++j) sizes[octant[j]] += !kept[j];
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
  const std::vector<Eigen::Vector3d> t =
      CubePositions(records, n, record_length, scale, offset, &tree);
  if (n == 0) return tree;
  const double min_scale = scale.cwiseAbs().minCoeff();
  std::vector<CopcNode> level(1);
  level[0].points.resize(n);
  for (size_t i = 0; i < n; ++i) level[0].points[i] = i;
  while (!level.empty()) {
    // Cells narrower than a LAS unit: only duplicates share one; keep them all here.
    const double cell = std::ldexp(tree.spacing, -level[0].key.level);
    const bool keep_all = cell < min_scale || level[0].key.level + kCellBits >= 62;
    std::vector<Split> splits(level.size());
    ParallelFor(size_t{0}, level.size(), [&](size_t j) {
      splits[j] = SplitNode(options, level[j].key, level[j].points, t, keep_all);
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

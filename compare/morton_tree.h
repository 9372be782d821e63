// MortonTree, the spatial index of the deviation methods: a binary radix tree over points in
// Morton order (MortonOrder), not a kd-tree; included by compare/*.cc only.
//
// Sorted by their Morton codes (MortonCodes), the points of any octree cell are one run, so the
// tree needs no search for splits: a node's run splits where the first Morton bit in which its
// ends differ turns to 1 (a binary search), which halves its cell along one axis, down to leaves
// of at most kLeafPoints points. Building it takes a pass over the points and one over the nodes
// (a kd-tree's build, nanoflann's in Debian 12 on one thread, cost as much as all the queries of
// a comparison). Node boxes are the boxes of their points, in floats rounded outwards, so pruning
// by them never skips a point; distances are the points' own, in double, exact. A query descends
// nearer child first. The tree depends on the points only, so results do not depend on the
// threads. Where two points are equally near, a query names the first it meets (the distance
// does not depend on which). Points out of Morton order give a correct but slower tree.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "compare/deviation.h"
#include "compare/deviation_internal.h"

namespace candi::compare::internal {

class MortonTree {
 public:
  static constexpr size_t kLeafPoints = 12;  // points a leaf, at most (but for coincident codes)

  // `points`' elements (finite, best in Morton order) must outlive the tree, unchanged; the
  // vector itself may be moved (the tree keeps its buffer, not the vector).
  explicit MortonTree(const std::vector<Eigen::Vector3d>& points) : points_(points.data()), size_(points.size()) {
    if (size_ == 0) return;
    const std::vector<uint64_t> codes = MortonCodes(points);
    sorted_ = std::is_sorted(codes.begin(), codes.end());
    nodes_.reserve(4 * (size_ / kLeafPoints + 1));
    parent_.reserve(nodes_.capacity());
    nodes_.push_back({});
    Build(0, codes, 0, static_cast<uint32_t>(size_));
  }

  size_t size() const { return size_; }
  const Eigen::Vector3d& point(size_t i) const { return points_[i]; }

  // The point nearest q; the search starts bounded by point `hint` (an index, or -1). Returns
  // its index (-1 only for an empty tree).
  int64_t Nearest(const Eigen::Vector3d& q, int64_t hint) const {
    int64_t best = -1;
    double best_sq = kInf;
    const auto bound = [&] { return best_sq; };
    const auto meet = [&](size_t i, double d) {
      if (d < best_sq) best_sq = d, best = static_cast<int64_t>(i);
    };
    if (hint < 0) {
      Search(0, q, bound, meet);
      return best;
    }
    // From the hint's leaf up: the leaf, then at each level the sibling subtree when its box is
    // nearer than the best so far (queries in Morton order meet their answer near the
    // previous one's, and skip the descent from the root).
    best = hint;
    best_sq = (q - points_[static_cast<size_t>(hint)]).squaredNorm();
    uint32_t node = 0;
    while (nodes_[node].child != 0) {
      const uint32_t c = nodes_[node].child;
      node = static_cast<uint64_t>(hint) < nodes_[c].end ? c : c + 1;
    }
    Search(node, q, bound, meet);
    while (node != 0) {
      const uint32_t parent = parent_[node];
      const uint32_t sibling = node == nodes_[parent].child ? node + 1 : node - 1;
      Search(sibling, q, bound, meet);
      node = parent;
    }
    return best;
  }

  // The k nearest points, nearest first: their indices and squared distances. Returns how many
  // (k, or fewer when the tree holds fewer).
  size_t Knn(const Eigen::Vector3d& q, size_t k, uint32_t* index, double* dist_sq) const {
    if (k == 0) return 0;
    size_t count = 0;
    Search(0, q, [&] { return count < k ? kInf : dist_sq[k - 1]; }, [&](size_t i, double d) {
      if (count == k && !(d < dist_sq[k - 1])) return;
      size_t j = count < k ? count++ : k - 1;  // insertion: k is small
      while (j > 0 && dist_sq[j - 1] > d) {
        dist_sq[j] = dist_sq[j - 1];
        index[j] = index[j - 1];
        --j;
      }
      dist_sq[j] = d;
      index[j] = static_cast<uint32_t>(i);
    });
    return count;
  }

  // Calls visit(index, dist_sq) for every point within `radius` of q.
  template <typename Visit>
  void ForEachWithin(const Eigen::Vector3d& q, double radius, Visit visit) const {
    const double radius_sq = radius * radius;
    // (A node is entered when its box is nearer than the bound: on the sphere counts as within.)
    const double bound = std::nextafter(radius_sq, kInf);
    Search(0, q, [bound] { return bound; }, [&](size_t i, double d) {
      if (d <= radius_sq) visit(static_cast<uint32_t>(i), d);
    });
  }

 private:
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  // A node: the box of its points in floats rounded outwards, its run of points, and its first
  // child (the second follows it; 0: a leaf).
  struct Node {
    float lo[3], hi[3];
    uint32_t begin, end, child;
    double DistSq(const Eigen::Vector3d& q) const {
      double sq = 0;
      for (int a = 0; a < 3; ++a) {
        const double g = std::max({0.0, static_cast<double>(lo[a]) - q[a], q[a] - static_cast<double>(hi[a])});
        sq += g * g;
      }
      return sq;
    }
  };

  // Fills node `at` with the run [begin, end) and its subtree (depth first; codes sorted).
  void Build(size_t at, const std::vector<uint64_t>& codes, uint32_t begin, uint32_t end) {
    uint32_t split = end;
    const uint64_t differ = codes[begin] ^ codes[end - 1];
    if (end - begin > kLeafPoints && !sorted_) {
      split = begin + (end - begin) / 2;  // out of Morton order: halves (a correct, looser tree)
    } else if (end - begin > kLeafPoints && differ != 0) {
      // The first bit in which the run's ends differ: 0 before the split, 1 from it on.
      const uint64_t bit = uint64_t{1} << (63 - __builtin_clzll(differ));
      split = static_cast<uint32_t>(
          std::partition_point(codes.begin() + begin, codes.begin() + end, [bit](uint64_t c) { return !(c & bit); }) -
          codes.begin());
    }
    double lo[3] = {kInf, kInf, kInf}, hi[3] = {-kInf, -kInf, -kInf};
    uint32_t child = 0;
    if (split == end) {
      for (uint32_t i = begin; i < end; ++i) {
        for (int a = 0; a < 3; ++a) {
          lo[a] = std::min(lo[a], points_[i][a]);
          hi[a] = std::max(hi[a], points_[i][a]);
        }
      }
    } else {
      child = static_cast<uint32_t>(nodes_.size());
      nodes_.push_back({});
      nodes_.push_back({});
      parent_.resize(nodes_.size());
      parent_[child] = parent_[child + 1] = static_cast<uint32_t>(at);
      Build(child, codes, begin, split);
      Build(child + 1, codes, split, end);
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::min(nodes_[child].lo[a], nodes_[child + 1].lo[a]);
        hi[a] = std::max(nodes_[child].hi[a], nodes_[child + 1].hi[a]);
      }
    }
    Node& node = nodes_[at];
    node.begin = begin;
    node.end = end;
    node.child = child;
    for (int a = 0; a < 3; ++a) {
      node.lo[a] = static_cast<float>(lo[a]);
      if (static_cast<double>(node.lo[a]) > lo[a]) node.lo[a] = std::nextafter(node.lo[a], -HUGE_VALF);
      node.hi[a] = static_cast<float>(hi[a]);
      if (static_cast<double>(node.hi[a]) < hi[a]) node.hi[a] = std::nextafter(node.hi[a], HUGE_VALF);
    }
  }

  // The subtree of `start`, depth first, nearer child first: a node is entered while its box is
  // nearer than bound() (which may shrink as points are met); every point of an entered leaf
  // goes to meet(i, dist_sq).
  template <typename Bound, typename Meet>
  void Search(uint32_t start, const Eigen::Vector3d& q, Bound bound, Meet meet) const {
    if (nodes_.empty()) return;
    struct Entry {
      uint32_t node;
      double dist_sq;
    };
    // Depth first, each node's children pushed as it is taken: at most the depth + 1 entries (a
    // sorted tree's depth is at most 63 code bits, an unsorted one's 32 halvings).
    Entry stack[128];
    int top = 0;
    stack[top++] = {start, nodes_[start].DistSq(q)};
    while (top > 0) {
      const Entry e = stack[--top];
      if (!(e.dist_sq < bound())) continue;
      const Node& node = nodes_[e.node];
      if (node.child == 0) {
        for (uint32_t i = node.begin; i < node.end; ++i) meet(i, (q - points_[i]).squaredNorm());
        continue;
      }
      const Entry a{node.child, nodes_[node.child].DistSq(q)}, b{node.child + 1, nodes_[node.child + 1].DistSq(q)};
      if (a.dist_sq <= b.dist_sq) {
        stack[top++] = b;
        stack[top++] = a;
      } else {
        stack[top++] = a;
        stack[top++] = b;
      }
    }
  }

  const Eigen::Vector3d* points_;
  size_t size_;
  bool sorted_ = true;       // the points in Morton order
  std::vector<Node> nodes_;  // nodes_[0] the root
  std::vector<uint32_t> parent_;  // of each node but the root
};

// M3C2 (m3c2.cc) of `compared` (NaN where not finite) against `reference` (finite, with its
// tree), the scales resolved (D and d > 0).
DeviationResult M3c2(const DeviationOptions& options, const std::vector<Eigen::Vector3d>& reference,
                     const MortonTree& reference_tree, const std::vector<Eigen::Vector3d>& compared,
                     const ProgressCallback& progress);

}  // namespace candi::compare::internal

// The COPC octree on records made in code: every point in exactly one node, each node's points
// inside its cube and at most one a cell of its grid (the spacing halving per level), children
// under their parents, duplicates kept together, the same tree on one and two threads.
#include "io/copc/copc_octree.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include "core/binary_file.h"
#include "core/spill_file.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

namespace util = ::candi::testing;

constexpr size_t kLength = 30;  // format 6
const Eigen::Vector3d kOctreeScale = Eigen::Vector3d::Constant(0.001);
const Eigen::Vector3d kOffset(500000.0, 4500000.0, 100.0);
// The grid alone: no small nodes folded into their parents.
const CopcOctreeOptions kGridOnly{0, 0};

// A clustered cloud: a wavy 60 m x 40 m floor, a dense 1 m cube, and 500 copies of one point.
std::vector<uint8_t> ClusteredRecords(size_t n, uint32_t seed) {
  std::vector<uint8_t> records(n * kLength, 0);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (size_t i = 0; i < n; ++i) {
    Eigen::Vector3d p;
    if (i % 10 == 0) {
      p = Eigen::Vector3d(20.0 + u(rng), 10.0 + u(rng), 3.0 + u(rng));
    } else if (i < 500) {
      p = Eigen::Vector3d(7.25, 8.5, 1.125);
    } else {
      const double x = 60.0 * u(rng), y = 40.0 * u(rng);
      p = Eigen::Vector3d(x, y, std::sin(0.3 * x) + 0.5 * std::cos(0.2 * y));
    }
    for (int k = 0; k < 3; ++k) {
      StoreLE<int32_t>(records.data() + i * kLength + 4 * k,
                       static_cast<int32_t>(std::lround(p[k] / kOctreeScale[k])));
    }
    records[i * kLength + 12] = static_cast<uint8_t>(i);
  }
  return records;
}

Eigen::Vector3d World(const std::vector<uint8_t>& records, uint64_t i,
                      const Eigen::Vector3d& scale = kOctreeScale,
                      const Eigen::Vector3d& offset = kOffset) {
  Eigen::Vector3d w;
  for (int k = 0; k < 3; ++k) {
    w[k] = LoadLE<int32_t>(records.data() + i * kLength + 4 * k) * scale[k] + offset[k];
  }
  return w;
}

std::tuple<int, int, int, int> Tuple(const CopcKey& k) { return {k.level, k.x, k.y, k.z}; }

TEST(CopcOctree, EveryPointOnceInsideItsNodeOnePerCell) {
  const size_t n = 200000;
  const std::vector<uint8_t> records = ClusteredRecords(n, 3);
  const CopcOctree tree = BuildCopcOctree(kGridOnly, records.data(), n, kLength, kOctreeScale, kOffset);
  EXPECT_NEAR(tree.halfsize, 30.0, 0.01);  // the floor's 60 m
  EXPECT_DOUBLE_EQ(tree.spacing, 2.0 * tree.halfsize / 128);
  std::vector<int> seen(n, 0);
  std::set<std::tuple<int, int, int, int>> keys;
  int depth = 0;
  for (const CopcNode& node : tree.nodes) {
    ASSERT_FALSE(node.points.empty());
    EXPECT_TRUE(keys.insert(Tuple(node.key)).second) << "a key twice";
    if (node.key.level > 0) {
      const CopcKey parent{node.key.level - 1, node.key.x / 2, node.key.y / 2, node.key.z / 2};
      EXPECT_TRUE(keys.count(Tuple(parent))) << "a node before its parent, or without one";
    }
    depth = std::max(depth, node.key.level);
    const Eigen::Vector3d lo = tree.NodeMin(node.key);
    const double width = tree.NodeWidth(node.key), cell = tree.spacing / (1 << node.key.level);
    const double tolerance = 1e-9 * tree.halfsize;
    std::set<std::tuple<int64_t, int64_t, int64_t>> cells;
    for (uint64_t i : node.points) {
      ++seen[i];
      const Eigen::Vector3d w = World(records, i);
      for (int k = 0; k < 3; ++k) {
        ASSERT_GE(w[k], lo[k] - tolerance);
        ASSERT_LE(w[k], lo[k] + width + tolerance);
      }
      // The node's grid: one point a cell (cells wider than a LAS unit; the deepest node holds
      // the 500 duplicates together).
      // A point within 1 um of a cell's face may be on either side of it (rounding): skipped.
      const Eigen::Vector3d u = (w - lo) / cell;
      const Eigen::Vector3d a = (u.array() - 1e-6 / cell).floor();
      const bool on_face = a != (u.array() + 1e-6 / cell).floor().matrix();
      if (cell >= kOctreeScale.minCoeff() && !on_face) {
        const Eigen::Vector3d c = a.array().max(0.0).min(127.0);
        EXPECT_TRUE(cells.insert({int64_t(c.x()), int64_t(c.y()), int64_t(c.z())}).second)
            << "two points in a cell of node level " << node.key.level;
      }
    }
  }
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(seen[i], 1) << "point " << i;
  EXPECT_GT(depth, 3);
  EXPECT_LT(depth, 20);
  std::printf("%zu points: %zu nodes, depth %d\n", n, tree.nodes.size(), depth);
}

TEST(CopcOctree, KeepsThePointNearestTheCellCentre) {
  // Two points in the root's first cell (width 1 m: a 128 m cube): the nearer the centre stays.
  std::vector<uint8_t> records(3 * kLength, 0);
  const int32_t xs[3] = {100, 450, 128000};  // 0.1 m, 0.45 m, 128 m
  for (int i = 0; i < 3; ++i) StoreLE<int32_t>(records.data() + i * kLength, xs[i]);
  const CopcOctree tree =
      BuildCopcOctree(kGridOnly, records.data(), 3, kLength, kOctreeScale, Eigen::Vector3d::Zero());
  ASSERT_EQ(tree.nodes.size(), 2u);
  EXPECT_EQ(tree.nodes[0].points, (std::vector<uint64_t>{1, 2}));
  EXPECT_EQ(tree.nodes[1].points, (std::vector<uint64_t>{0}));
  EXPECT_EQ(Tuple(tree.nodes[1].key), std::make_tuple(1, 0, 1, 1));  // y, z: the cube's middle
}

TEST(CopcOctree, SameTreeOnOneAndTwoThreads) {
  const size_t n = 100000;
  const std::vector<uint8_t> records = ClusteredRecords(n, 9);
  CopcOctree a, b;
  tbb::task_arena one(1), two(2);
  const CopcOctreeOptions defaults;
  one.execute([&] { a = BuildCopcOctree(defaults, records.data(), n, kLength, kOctreeScale, kOffset); });
  two.execute([&] { b = BuildCopcOctree(defaults, records.data(), n, kLength, kOctreeScale, kOffset); });
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  for (size_t j = 0; j < a.nodes.size(); ++j) {
    EXPECT_TRUE(a.nodes[j].key == b.nodes[j].key);
    EXPECT_EQ(a.nodes[j].points, b.nodes[j].points);
  }
}

TEST(CopcOctree, SmallNodesStayInTheirParentsAsInUntwine) {
  const size_t n = 200000;
  const std::vector<uint8_t> records = ClusteredRecords(n, 3);
  const CopcOctreeOptions defaults;
  const CopcOctree grid = BuildCopcOctree(kGridOnly, records.data(), n, kLength, kOctreeScale, kOffset);
  const CopcOctree tree = BuildCopcOctree(defaults, records.data(), n, kLength, kOctreeScale, kOffset);
  std::map<std::tuple<int, int, int, int>, uint64_t> subtree;  // points at or below a node
  std::vector<int> seen(n, 0);
  for (auto it = tree.nodes.rbegin(); it != tree.nodes.rend(); ++it) {
    for (uint64_t i : it->points) ++seen[i];
    subtree[Tuple(it->key)] += it->points.size();
    if (it->key.level > 0) {
      const CopcKey parent{it->key.level - 1, it->key.x / 2, it->key.y / 2, it->key.z / 2};
      subtree[Tuple(parent)] += subtree[Tuple(it->key)];
    }
  }
  for (size_t i = 0; i < n; ++i) ASSERT_EQ(seen[i], 1) << "point " << i;
  for (const CopcNode& node : tree.nodes) {
    if (node.key.level == 0) continue;
    EXPECT_GE(subtree[Tuple(node.key)], 100u) << "a node of fewer than min_octant_points";
    const CopcKey parent{node.key.level - 1, node.key.x / 2, node.key.y / 2, node.key.z / 2};
    EXPECT_GE(subtree[Tuple(parent)], 1500u) << "children under fewer than min_subtree_points";
  }
  EXPECT_LT(tree.nodes.size(), grid.nodes.size());
  std::printf("%zu nodes with untwine's minimums, %zu with the grid alone\n", tree.nodes.size(),
              grid.nodes.size());
}

// The header's rule written as plainly as it reads: each node's points by their cell on a map,
// the nearest to the cell's centre (its squared distance as a float, then the earlier point)
// staying; the rest to their octants, octants of too few points staying too.
class ReferenceTree {
 public:
  ReferenceTree(const CopcOctreeOptions& options, const std::vector<uint8_t>& records, size_t n,
                const CopcOctree& cube, const Eigen::Vector3d& scale = kOctreeScale,
                const Eigen::Vector3d& offset = kOffset)
      : options_(options), places_(n), min_scale_(scale.minCoeff()) {
    const Eigen::Vector3d min = cube.center.array() - cube.halfsize;
    const long double one = std::ldexp(1.0L, 62);
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d t = (World(records, i, scale, offset) - min) / (2.0 * cube.halfsize);
      for (int k = 0; k < 3; ++k) {
        const long double u = std::floor(static_cast<long double>(t[k]) * one);
        places_[i][k] = u <= 0 ? 0 : u >= one ? (uint64_t{1} << 62) - 1 : uint64_t(u);
      }
    }
    spacing_ = cube.spacing;
  }

  std::map<std::tuple<int, int, int, int>, std::vector<uint64_t>> Build() {
    std::vector<uint64_t> all(places_.size());
    for (size_t i = 0; i < all.size(); ++i) all[i] = i;
    Split(CopcKey{}, all);
    return nodes_;
  }

 private:
  void Split(const CopcKey& key, const std::vector<uint64_t>& points) {
    std::vector<uint64_t>& kept = nodes_[Tuple(key)];
    const bool keep_all = std::ldexp(spacing_, -key.level) < min_scale_;
    if (keep_all || points.size() < static_cast<size_t>(options_.min_subtree_points)) {
      kept = points;
      return;
    }
    const int shift = 62 - (key.level + 7);
    std::map<std::tuple<uint64_t, uint64_t, uint64_t>, std::pair<float, uint64_t>> best;
    for (uint64_t i : points) {
      double d = 0.0;
      for (int k = 0; k < 3; ++k) {
        const double e = std::ldexp(double(places_[i][k] & ((uint64_t{1} << shift) - 1)), -shift);
        d += (e - 0.5) * (e - 0.5);
      }
      const auto cell =
          std::make_tuple(places_[i][0] >> shift, places_[i][1] >> shift, places_[i][2] >> shift);
      const auto candidate = std::make_pair(static_cast<float>(d), i);
      const auto it = best.find(cell);
      if (it == best.end() || candidate < it->second) best[cell] = candidate;
    }
    std::set<uint64_t> stays;
    for (const auto& [cell, b] : best) stays.insert(b.second);
    std::array<std::vector<uint64_t>, 8> octants;
    for (uint64_t i : points) {
      if (stays.count(i)) continue;
      int o = 0;
      for (int k = 0; k < 3; ++k) o |= int((places_[i][k] >> (61 - key.level)) & 1) << k;
      octants[o].push_back(i);
    }
    for (int o = 0; o < 8; ++o) {
      if (octants[o].size() < static_cast<size_t>(options_.min_octant_points)) {
        stays.insert(octants[o].begin(), octants[o].end());
      }
    }
    kept.assign(stays.begin(), stays.end());
    for (int o = 0; o < 8; ++o) {
      if (octants[o].empty() || octants[o].size() < size_t(options_.min_octant_points)) continue;
      Split({key.level + 1, 2 * key.x + (o & 1), 2 * key.y + (o >> 1 & 1), 2 * key.z + (o >> 2)},
            octants[o]);
    }
  }

  const CopcOctreeOptions options_;
  std::vector<std::array<uint64_t, 3>> places_;
  double min_scale_ = 0.0, spacing_ = 0.0;
  std::map<std::tuple<int, int, int, int>, std::vector<uint64_t>> nodes_;
};

// Compares the tree of n records with the rule's, node by node; returns the depth.
int ExpectTheRulesTree(const CopcOctreeOptions& options, const std::vector<uint8_t>& records,
                       size_t n, const Eigen::Vector3d& scale, const Eigen::Vector3d& offset) {
  const CopcOctree tree = BuildCopcOctree(options, records.data(), n, kLength, scale, offset);
  const auto reference = ReferenceTree(options, records, n, tree, scale, offset).Build();
  EXPECT_EQ(tree.nodes.size(), reference.size());
  int previous_level = 0;
  for (const CopcNode& node : tree.nodes) {
    EXPECT_GE(node.key.level, previous_level) << "nodes level by level";
    previous_level = node.key.level;
    const auto it = reference.find(Tuple(node.key));
    if (it == reference.end()) {
      ADD_FAILURE() << "no node " << node.key.level << "-" << node.key.x << "-" << node.key.y << "-"
                    << node.key.z << " in the rule's tree";
      break;
    }
    EXPECT_EQ(node.points, it->second);
    EXPECT_EQ(node.size, node.points.size());
  }
  return previous_level;
}

TEST(CopcOctree, TheMortonBuildGivesTheRulesTree) {
  // 150,000 points: the root and the first levels take the large nodes' way (blocks of cells on
  // every thread), the rest the small nodes' (a thread each).
  // The sort's scratch cut down: groups sorted in place (all, or those over 100 points).
  const size_t n = 150000;
  const std::vector<uint8_t> records = ClusteredRecords(n, 11);
  const CopcOctreeOptions in_place{1500, 100, 0}, mixed{0, 0, 100};
  for (const CopcOctreeOptions& options : {kGridOnly, CopcOctreeOptions{}, in_place, mixed}) {
    SCOPED_TRACE(options.sort_scratch_points);
    ExpectTheRulesTree(options, records, n, kOctreeScale, kOffset);
  }
}

TEST(CopcOctree, LatticesOfBinaryFractionsGiveTheRulesTree) {
  // A 128 m cube (corners (0, 0, 0) and (128, 128, 128): the root's cells are 1 m) and a lattice
  // in it, in shuffled order. Steps of 1/8 m from 0: points on the faces of the subcells whose
  // bounds skip distances, and at cells' centres. Steps of 1/4 m from 1/8 m: eight points of a
  // cell equally near its centre, at the least distance its subcells allow (the earlier stays).
  for (const int32_t step : {125, 250}) {
    const int32_t from = step == 125 ? 0 : 125, side = 4000 / step;
    std::vector<std::array<int32_t, 3>> points{{0, 0, 0}, {128000, 128000, 128000}};
    for (int32_t x = 0; x < side; ++x) {
      for (int32_t y = 0; y < side; ++y) {
        for (int32_t z = 0; z < 8; ++z) {
          points.push_back({from + step * x, from + step * y, from + step * z + 250});
        }
      }
    }
    std::shuffle(points.begin() + 2, points.end(), std::mt19937(23));
    const size_t n = points.size();
    std::vector<uint8_t> records(n * kLength, 0);
    for (size_t i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) {
        StoreLE<int32_t>(records.data() + i * kLength + 4 * k, points[i][k]);
      }
    }
    const Eigen::Vector3d origin = Eigen::Vector3d::Zero();
    for (const CopcOctreeOptions& options : {kGridOnly, CopcOctreeOptions{}}) {
      SCOPED_TRACE(step);
      EXPECT_GT(ExpectTheRulesTree(options, records, n, kOctreeScale, origin), 0);
    }
  }
}

TEST(CopcOctree, NodesDeeperThanTheKeysHoldAreKeyedAgain) {
  // A 2 mm cluster of micrometre points (a scale of 1 um) between two points 2 km apart: nodes
  // go 24 levels down, past the 14 levels below a base that a Morton key holds with its cells.
  const size_t n = 40000;
  const Eigen::Vector3d scale = Eigen::Vector3d::Constant(1e-6), offset(700000.0, 0.0, 0.0);
  std::vector<uint8_t> records(n * kLength, 0);
  std::mt19937 rng(17);
  std::uniform_int_distribution<int32_t> um(0, 2000);
  for (size_t i = 0; i < n; ++i) {
    int32_t p[3] = {300000 + um(rng), 200000 + um(rng), 100000 + um(rng)};
    if (i == 0 || i == 1) p[0] = i == 0 ? -1000000000 : 1000000000;
    if (i >= 2 && i < 3002) p[0] = p[1] = p[2] = 301234;  // duplicates: a chain of nodes
    for (int k = 0; k < 3; ++k) StoreLE<int32_t>(records.data() + i * kLength + 4 * k, p[k]);
  }
  for (const CopcOctreeOptions& options : {kGridOnly, CopcOctreeOptions{}, {0, 0, 0}}) {
    const int depth = ExpectTheRulesTree(options, records, n, scale, offset);
    EXPECT_GT(depth, 21) << "the tree must reach past a second base";
  }
}

TEST(CopcOctree, TheRecordsIntegerBoundsGiveTheSameTreeAsTheirPass) {
  // A writer passes the X, Y, Z bounds it tracked instead of a pass over the records: the cube
  // and every point's node must be the same, for a positive and a negative scale (whose least
  // world coordinate is the greatest integer's) and for an offset that cancels a position.
  const size_t n = 50000;
  const std::vector<uint8_t> records = ClusteredRecords(n, 7);
  CopcXyzBounds bounds;
  bounds[0].fill(std::numeric_limits<int32_t>::max());
  bounds[1].fill(std::numeric_limits<int32_t>::min());
  for (size_t i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      const int32_t v = LoadLE<int32_t>(records.data() + i * kLength + 4 * k);
      bounds[0][k] = std::min(bounds[0][k], v);
      bounds[1][k] = std::max(bounds[1][k], v);
    }
  }
  const double cancel = -bounds[0][0] * 0.25;
  for (const auto& [scale, offset] :
       {std::pair{kOctreeScale, kOffset},
        std::pair{Eigen::Vector3d(-0.001, 0.01, -0.25), Eigen::Vector3d(5e5, -3.0, 0.0)},
        std::pair{Eigen::Vector3d::Constant(0.25).eval(), Eigen::Vector3d(cancel, 0.0, -0.0)}}) {
    const CopcOctree pass = BuildCopcOctree({}, records.data(), n, kLength, scale, offset);
    const CopcOctree known =
        BuildCopcOctree({}, records.data(), n, kLength, scale, offset, &bounds);
    EXPECT_EQ(known.center, pass.center) << scale.transpose();
    EXPECT_EQ(known.halfsize, pass.halfsize);
    ASSERT_EQ(known.nodes.size(), pass.nodes.size());
    for (size_t j = 0; j < pass.nodes.size(); ++j) {
      ASSERT_TRUE(known.nodes[j].key == pass.nodes[j].key);
      ASSERT_EQ(known.nodes[j].points, pass.nodes[j].points);
    }
  }
}

TEST(CopcOctreeOptions, DefaultsPassAndNegativeMinimumsAreRefused) {
  EXPECT_NO_THROW(CopcOctreeOptions().Check());
  CopcOctreeOptions o;
  o.min_subtree_points = -1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.min_octant_points = -5;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.bucket_points = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.batch_points = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

TEST(CopcOctree, EmptyAndSinglePoint) {
  EXPECT_TRUE(BuildCopcOctree({}, nullptr, 0, kLength, kOctreeScale, kOffset).nodes.empty());
  std::vector<uint8_t> one(kLength, 0);
  const CopcOctree tree = BuildCopcOctree({}, one.data(), 1, kLength, kOctreeScale, kOffset);
  ASSERT_EQ(tree.nodes.size(), 1u);
  EXPECT_GT(tree.halfsize, 0.0);
}

TEST(CopcOctree, AnyBucketSizeGivesTheRulesTree) {
  // Buckets of at most 1 point (every bucket a cell at level 7, or one that cannot be cut), of a
  // few and of many: the levels above each bucket are built in it, their rules from every
  // bucket's counts. The clustered cloud's fringes fold small octants and subtrees into nodes
  // above the buckets.
  const size_t n = 60000;
  const std::vector<uint8_t> records = ClusteredRecords(n, 13);
  for (const size_t bucket : {size_t{1}, size_t{40}, size_t{1000}, size_t{20000}}) {
    for (CopcOctreeOptions options : {kGridOnly, CopcOctreeOptions{}, CopcOctreeOptions{300, 20}}) {
      options.bucket_points = bucket;
      options.batch_points = 5000;
      SCOPED_TRACE(::testing::Message()
                   << bucket << " points a bucket, minimums " << options.min_subtree_points << ", "
                   << options.min_octant_points);
      ExpectTheRulesTree(options, records, n, kOctreeScale, kOffset);
    }
  }
}

// Two corners of a 1,024 m cube, a dense 10 m floor near one, and `far` points within 1 m near
// the other: the far points' octant of the root, a node above small buckets, has fewer points
// than the minimums.
std::vector<uint8_t> FarClusterRecords(size_t n, size_t far) {
  std::vector<uint8_t> records(n * kLength, 0);
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (size_t i = 0; i < n; ++i) {
    Eigen::Vector3d p(10.0 * u(rng), 10.0 * u(rng), 0.1 * u(rng));
    if (i == 0) p = Eigen::Vector3d::Zero();
    if (i == 1) p = Eigen::Vector3d::Constant(1024.0);
    if (i >= 2 && i < 2 + far)
      p = Eigen::Vector3d::Constant(1000.0) + Eigen::Vector3d(u(rng), u(rng), u(rng));
    for (int k = 0; k < 3; ++k) {
      StoreLE<int32_t>(records.data() + i * kLength + 4 * k,
                       static_cast<int32_t>(std::lround(p[k] / kOctreeScale[k])));
    }
  }
  return records;
}

TEST(CopcOctree, NodesAboveTheBucketsFoldTheirSubtreesAndOctants) {
  // Buckets of 16 points: the far cluster's octant is cut into buckets down to level 7, so its
  // rules are decided above them. 300 far points: the octant's node is reached by fewer than 1500
  // and keeps them all; 60: fewer than 100 reach the octant, which stays in the root.
  const size_t n = 20000;
  const CopcKey far_octant{1, 1, 1, 1};
  for (const size_t far : {size_t{300}, size_t{60}}) {
    SCOPED_TRACE(far);
    const std::vector<uint8_t> records = FarClusterRecords(n, far);
    CopcOctreeOptions options;
    options.bucket_points = 16;
    ExpectTheRulesTree(options, records, n, kOctreeScale, Eigen::Vector3d::Zero());
    const CopcOctree tree =
        BuildCopcOctree(options, records.data(), n, kLength, kOctreeScale, Eigen::Vector3d::Zero());
    size_t in_far_octant = 0, below_it = 0;
    for (const CopcNode& node : tree.nodes) {
      if (node.key.level == 0) continue;
      const int up = node.key.level - 1;
      const bool inside =
          (node.key.x >> up) == 1 && (node.key.y >> up) == 1 && (node.key.z >> up) == 1;
      if (node.key == far_octant) {
        in_far_octant = node.size;
      } else if (inside) {
        ++below_it;
      }
    }
    EXPECT_EQ(below_it, 0u) << "nodes under the far octant: its subtree must fold";
    if (far == 300) {
      EXPECT_GE(in_far_octant, 290u);
    } else {
      EXPECT_EQ(in_far_octant, 0u) << "the far octant must stay in the root";
    }
  }
}

TEST(CopcOctree, TheNodesComeBucketByBucketThenTheNodesAbove) {
  // BuildCopcNodes hands each node on once, with its records (contiguous, in input order) and
  // their indices; the nodes above the buckets last, level by level.
  const size_t n = 50000;
  const std::vector<uint8_t> records = ClusteredRecords(n, 19);
  CopcOctreeOptions options;
  options.bucket_points = 2000;
  const CopcOctree reference =
      BuildCopcOctree(options, records.data(), n, kLength, kOctreeScale, kOffset);
  std::map<std::tuple<int, int, int, int>, std::vector<uint64_t>> expected;
  for (const CopcNode& node : reference.nodes) expected[Tuple(node.key)] = node.points;
  std::vector<CopcKey> order;
  size_t encoded = 0;
  const CopcOctree tree = BuildCopcNodes(
      options, records.data(), n, kLength, kOctreeScale, kOffset, nullptr,
      [&](const CopcKey& key, const uint8_t* node_records, const uint32_t* indices, size_t count,
          std::vector<uint8_t>* out) {
        EXPECT_TRUE(out->empty());
        for (size_t k = 0; k < count; ++k) {
          ASSERT_EQ(std::memcmp(node_records + k * kLength,
                                records.data() + size_t{indices[k]} * kLength, kLength),
                    0);
          if (k > 0) {
            ASSERT_LT(indices[k - 1], indices[k]) << "input order";
          }
        }
        out->assign(1, static_cast<uint8_t>(key.level));
      },
      [&](const CopcKey& key, uint64_t count, std::vector<uint8_t>* out) {
        ASSERT_EQ(out->size(), 1u);
        EXPECT_EQ((*out)[0], key.level);
        EXPECT_EQ(count, expected[Tuple(key)].size());
        order.push_back(key);
        ++encoded;
      });
  EXPECT_EQ(encoded, reference.nodes.size());
  ASSERT_EQ(tree.nodes.size(), order.size());
  for (size_t j = 0; j < order.size(); ++j) EXPECT_TRUE(tree.nodes[j].key == order[j]);
  // The root is above the buckets (there are several), so it comes in the last run, which goes
  // level by level.
  size_t root = order.size();
  for (size_t j = 0; j < order.size(); ++j) {
    if (order[j].level == 0) root = j;
  }
  ASSERT_LT(root, order.size());
  for (size_t j = root + 1; j < order.size(); ++j) EXPECT_GE(order[j].level, order[j - 1].level);
  EXPECT_GT(root, 0u) << "the buckets' nodes first";
}

// The records spilled to a file in dir, as a writer spills them.
struct Spilled {
  std::unique_ptr<SpillFile> file;
  CopcRecords input;
};
Spilled Spill(const std::vector<uint8_t>& records, size_t n, const std::string& dir,
              size_t memory_points) {
  Spilled s;
  s.file = std::make_unique<SpillFile>(dir + "/records.spill");
  s.file->Append(records.data(), n * kLength);
  s.input.spill = s.file.get();
  s.input.n = n;
  s.input.record_length = kLength;
  s.input.memory_points = memory_points;
  s.input.spill_dir = dir;
  return s;
}

// The nodes BuildCopcNodes hands on, in order: key, count and what the encoder made of them.
std::vector<std::tuple<int, int, int, int, uint64_t, std::vector<uint8_t>>> HandedOn(
    const CopcOctreeOptions& options, const CopcRecords& input, const Eigen::Vector3d& offset) {
  std::vector<std::tuple<int, int, int, int, uint64_t, std::vector<uint8_t>>> out;
  BuildCopcNodes(
      options, input, kOctreeScale, offset, nullptr,
      [](const CopcKey&, const uint8_t* node_records, const uint32_t* indices, size_t count,
         std::vector<uint8_t>* bytes) {
        bytes->assign(node_records, node_records + count * kLength);
        const uint8_t* i = reinterpret_cast<const uint8_t*>(indices);
        bytes->insert(bytes->end(), i, i + 4 * count);
      },
      [&](const CopcKey& key, uint64_t count, std::vector<uint8_t>* bytes) {
        out.emplace_back(key.level, key.x, key.y, key.z, count, std::move(*bytes));
      });
  return out;
}

TEST(CopcOctree, ASpilledBuildHandsOnTheNodesOfTheBuildInMemory) {
  // Groups of at most 1, 3,000 or 25,000 points (a group of one bucket where a bucket is
  // larger): the same nodes, records and indices, in the same order, as the records in memory;
  // with folds above the buckets (the far cluster) too. The build's files are gone after it.
  util::TempDir dir;
  for (const bool far : {false, true}) {
    const size_t n = far ? 20000 : 60000;
    const std::vector<uint8_t> records = far ? FarClusterRecords(n, 300) : ClusteredRecords(n, 31);
    const Eigen::Vector3d offset = far ? Eigen::Vector3d::Zero() : kOffset;
    CopcOctreeOptions options;
    options.bucket_points = far ? 16 : 2000;
    CopcRecords in_memory;
    in_memory.data = records.data();
    in_memory.n = n;
    in_memory.record_length = kLength;
    const auto expected = HandedOn(options, in_memory, offset);
    ASSERT_GT(expected.size(), 10u);
    for (const size_t memory : {size_t{1}, size_t{3000}, size_t{25000}}) {
      SCOPED_TRACE(::testing::Message()
                   << (far ? "far cluster, " : "") << memory << " points a group");
      Spilled s = Spill(records, n, dir.path(), memory);
      const auto spilled = HandedOn(options, s.input, offset);
      ASSERT_EQ(spilled.size(), expected.size());
      for (size_t j = 0; j < expected.size(); ++j)
        ASSERT_TRUE(spilled[j] == expected[j]) << "node " << j;
      s.file.reset();
      EXPECT_TRUE(std::filesystem::is_empty(dir.path())) << "the build's files are left behind";
    }
  }
}

}  // namespace
}  // namespace candi::io

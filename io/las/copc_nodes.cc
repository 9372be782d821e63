// The bucket pipeline of io/las/copc_octree.h: the cube cut into buckets by the counts of its
// cells, each bucket's octree built and its nodes encoded alone (in the cache), the nodes above
// the buckets settled from every bucket's counts and encoded last.
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <numeric>
#include <tuple>
#include <vector>

#include "core/binary_file.h"
#include "core/check.h"
#include "core/parallel.h"
#include "io/las/copc_octree.h"
#include "io/las/copc_octree_internal.h"

namespace candi::io {

namespace {

using namespace copc_internal;

// Buckets are nodes of levels 0..kBucketLevel; the points' cells there are counted. A node above
// a bucket (level < kBucketLevel) has its cells (kCellBits levels down) whole in the bucket.
constexpr int kBucketLevel = 7;
static_assert(kBucketLevel <= kCellBits);
constexpr uint32_t kCells = uint32_t{1} << (3 * kBucketLevel);

// The nodes that can be above a bucket (levels 0..kBucketLevel - 1) by a flat index: level k's
// 8^k (by Morton code) after the levels above.
uint32_t LevelStart(int level) { return ((uint32_t{1} << (3 * level)) - 1) / 7; }
constexpr uint32_t kAboveNodes = (kCells - 1) / 7;
uint32_t AboveIndex(int level, uint32_t code) { return LevelStart(level) + code; }
int LevelOfIndex(uint32_t index) {
  int level = 0;
  while (level + 1 < kBucketLevel && LevelStart(level + 1) <= index) ++level;
  return level;
}

// node_of of a point that a node above its bucket keeps, at level k: kAbove + k.
constexpr uint32_t kAbove = 0xFFFFFF00u;
constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();

// The key of the node of Morton code `code` at `level` (its octants, level 1's highest).
CopcKey KeyOf(int level, uint32_t code) {
  CopcKey key{level, 0, 0, 0};
  for (int l = level - 1; l >= 0; --l) {
    const uint32_t o = code >> (3 * l) & 7;
    key.x = 2 * key.x + static_cast<int32_t>(o & 1);
    key.y = 2 * key.y + static_cast<int32_t>(o >> 1 & 1);
    key.z = 2 * key.z + static_cast<int32_t>(o >> 2 & 1);
  }
  return key;
}

// A bucket: node (level, code) and its points, list[begin, end) in input order.
struct Bucket {
  int level = 0;
  uint32_t code = 0;
  size_t begin = 0, end = 0;
  size_t size() const { return end - begin; }
};

// The code of the bucket's ancestor at `level` (<= its level).
uint32_t AncestorCode(const Bucket& b, int level) { return b.code >> (3 * (b.level - level)); }

// The records' X, Y, Z.
void LoadXyz(const uint8_t* record, int32_t* xyz) {
  for (int k = 0; k < 3; ++k) xyz[k] = LoadLE<int32_t>(record + 4 * k);
}

// The deepest level a bucket may have: kBucketLevel, or the first level whose cells are
// narrower than a LAS unit (whose nodes keep all their points: no node above a bucket may).
int DeepestBucketLevel(const CopcOctree& tree, double min_scale) {
  for (int level = 0; level < kBucketLevel; ++level) {
    if (std::ldexp(tree.spacing, -level) < min_scale) return level;
  }
  return kBucketLevel;
}

// Cuts the n points into buckets (in Morton order): every point's cell at kBucketLevel counted
// (by parallel blocks into each thread's counts), the nodes of more than max_points points split
// down to max_level; their points listed into `list` in input order.
std::vector<Bucket> CutBuckets(const uint8_t* records, size_t n, size_t length, const Cube& cube,
                               size_t max_points, int max_level, uint32_t* list,
                               const std::function<void(uint64_t, uint64_t)>& progress) {
  const std::unique_ptr<uint32_t[]> cells(new uint32_t[n]);
  tbb::enumerable_thread_specific<std::vector<uint32_t>> local_counts(
      [] { return std::vector<uint32_t>(kCells, 0); });
  ParallelFor(size_t{0}, (n + kBlock - 1) / kBlock, [&](size_t b) {
    std::vector<uint32_t>& counts = local_counts.local();
    for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
      int32_t xyz[3];
      LoadXyz(records + i * length, xyz);
      const uint32_t c =
          static_cast<uint32_t>(MortonCode(cube(xyz), 0) >> (3 * (kKeyLevels - kBucketLevel)));
      cells[i] = c;
      ++counts[c];
    }
  });
  if (progress) progress(n / 3, n);
  // Each level's counts, from the deepest up.
  std::array<std::vector<uint64_t>, kBucketLevel + 1> counts;
  counts[kBucketLevel].assign(kCells, 0);
  for (const std::vector<uint32_t>& c : local_counts) {
    for (uint32_t u = 0; u < kCells; ++u) counts[kBucketLevel][u] += c[u];
  }
  for (int level = kBucketLevel - 1; level >= 0; --level) {
    counts[level].assign(size_t{1} << (3 * level), 0);
    for (size_t u = 0; u < counts[level + 1].size(); ++u)
      counts[level][u >> 3] += counts[level + 1][u];
  }
  std::vector<Bucket> buckets;
  auto cut = [&](auto&& self, int level, uint32_t code) -> void {
    const uint64_t c = counts[level][code];
    if (c == 0) return;
    if (level == max_level || c <= max_points) {
      buckets.push_back({level, code, 0, 0});
      return;
    }
    for (uint32_t o = 0; o < 8; ++o) self(self, level + 1, code << 3 | o);
  };
  cut(cut, 0, 0);
  std::vector<uint32_t> bucket_of(kCells, kNone);
  for (size_t j = 0; j < buckets.size(); ++j) {
    const int shift = 3 * (kBucketLevel - buckets[j].level);
    std::fill(bucket_of.begin() + (size_t{buckets[j].code} << shift),
              bucket_of.begin() + (size_t{buckets[j].code + 1} << shift), static_cast<uint32_t>(j));
  }
  // The lists: blocks' counts of each bucket, then each block's points to their places (a
  // bucket's points in input order, whatever the thread count). At most 64 blocks, so the
  // counts (blocks x buckets) stay small however large n is.
  const size_t block = std::max(size_t{1} << 20, (n + 63) / 64);
  const size_t blocks = (n + block - 1) / block, m = buckets.size();
  std::vector<uint64_t> at(blocks * m, 0);
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    uint64_t* count = at.data() + b * m;
    for (size_t i = b * block; i < std::min(n, (b + 1) * block); ++i) ++count[bucket_of[cells[i]]];
  });
  size_t next = 0;
  for (size_t j = 0; j < m; ++j) {
    buckets[j].begin = next;
    for (size_t b = 0; b < blocks; ++b) {
      const uint64_t c = at[b * m + j];
      at[b * m + j] = next;
      next += c;
    }
    buckets[j].end = next;
  }
  CANDI_CHECK_EQ(next, n) << "COPC buckets";
  if (progress) progress(2 * (n / 3), n);
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    uint64_t* to = at.data() + b * m;
    for (size_t i = b * block; i < std::min(n, (b + 1) * block); ++i) {
      list[to[bucket_of[cells[i]]]++] = static_cast<uint32_t>(i);
    }
  });
  return buckets;
}

// A bucket's working memory (its records, their elements and nodes, the records in node order),
// kept from bucket to bucket; a pool hands each bucket in the works its own.
struct Scratch {
  std::unique_ptr<uint8_t[]> records, ordered;
  std::unique_ptr<Element[]> elements;
  std::unique_ptr<uint32_t[]> node_of, indices;
  size_t capacity = 0, record_bytes = 0;
  void Reserve(size_t points, size_t length) {
    if (points > capacity) {
      capacity = std::max(points, capacity + capacity / 2);
      elements.reset(new Element[capacity]);
      node_of.reset(new uint32_t[capacity]);
      indices.reset(new uint32_t[capacity]);
    }
    if (points * length > record_bytes) {
      record_bytes = std::max(points * length, record_bytes + record_bytes / 2);
      records.reset(new uint8_t[record_bytes]);
      ordered.reset(new uint8_t[record_bytes]);
    }
  }
};

class ScratchPool {
 public:
  std::unique_ptr<Scratch> Take() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (free_.empty()) return std::make_unique<Scratch>();
    std::unique_ptr<Scratch> s = std::move(free_.back());
    free_.pop_back();
    return s;
  }
  void Give(std::unique_ptr<Scratch> s) {
    std::lock_guard<std::mutex> lock(mutex_);
    free_.push_back(std::move(s));
  }

 private:
  std::mutex mutex_;
  std::vector<std::unique_ptr<Scratch>> free_;
};

// A bucket built: its own nodes (level by level, each level by (x, y, z)) encoded, the points
// that nodes above it keep, and what the rules above need.
struct BucketNodes {
  std::vector<CopcKey> keys;
  std::vector<uint64_t> sizes;
  std::vector<std::vector<uint8_t>> encoded;
  std::vector<uint64_t> above;  // AboveIndex << 32 | point index, of each point kept above
  std::array<uint64_t, kBucketLevel> kept{};  // points kept at each level above the bucket
  // Held: a node above may yet fold the bucket's points into itself; then its nodes' points
  // (local, in node order) go there too.
  bool held = false;
  std::vector<uint32_t> local;
};

// Buckets of at least this many points are built on several threads.
constexpr size_t kParallelBucket = size_t{1} << 20;

class NodeBuilder {
 public:
  NodeBuilder(const CopcOctreeOptions& options, const uint8_t* records, size_t length,
              const Cube& cube, const CopcOctree& tree, double min_scale, const uint32_t* list,
              const CopcNodeEncoder& encode)
      : options_(options),
        records_(records),
        length_(length),
        cube_(cube),
        tree_(tree),
        min_scale_(min_scale),
        list_(list),
        encode_(encode),
        sort_(options.sort_scratch_points) {}

  // Builds bucket `b` into *out.
  void Build(const Bucket& b, BucketNodes* out) {
    std::unique_ptr<Scratch> s = pool_.Take();
    const size_t m = b.size();
    const bool parallel = m >= kParallelBucket;
    s->Reserve(m, length_);
    const uint32_t* index = list_ + b.begin;
    Loop(parallel, (m + kBlock - 1) / kBlock, [&](size_t block) {
      for (size_t j = block * kBlock; j < std::min(m, (block + 1) * kBlock); ++j) {
        if (j + 16 < m) __builtin_prefetch(records_ + size_t{index[j + 16]} * length_);
        uint8_t* r = s->records.get() + j * length_;
        std::memcpy(r, records_ + size_t{index[j]} * length_, length_);
        Element& e = s->elements[j];
        LoadXyz(r, e.xyz);
        e.key = MortonCode(cube_(e.xyz), 0);
        e.index = static_cast<uint32_t>(j);
      }
    });
    sort_(s->elements.get(), m, 3 * kKeyLevels);
    Builder builder(options_, cube_, &sort_, s->elements.get(), s->node_of.get());
    // The levels above the bucket: the nearest point of each of their cells, no rule (counts
    // across buckets decide those). What passes on reaches the bucket's own node.
    size_t left = m;
    for (int k = 0; k < b.level; ++k) {
      const Range above{KeyOf(k, AncestorCode(b, k)), 0, m, left};
      const size_t passed = builder.KeepNearestOfCells(above, kAbove + static_cast<uint32_t>(k));
      out->kept[k] = left - passed;
      left = passed;
    }
    if (b.level > 0) {
      const size_t reaching_parent = left + out->kept[b.level - 1];
      out->held = reaching_parent < static_cast<size_t>(std::max(options_.min_subtree_points,
                                                                 options_.min_octant_points));
      if (left > 0 && left < static_cast<size_t>(options_.min_octant_points)) {  // its parent's
        builder.KeepAll(0, m, kAbove + static_cast<uint32_t>(b.level - 1), false);
        out->kept[b.level - 1] += left;
        left = 0;
      }
    }
    if (left > 0) BuildLevels(b, left, parallel, &builder, out);
    Gather(b, *s, out);
    const size_t nodes = out->keys.size();
    out->encoded.resize(nodes);
    std::vector<size_t> first(nodes + 1, 0);
    for (size_t j = 0; j < nodes; ++j) first[j + 1] = first[j] + out->sizes[j];
    Loop(parallel, nodes, [&](size_t j) {
      encode_(out->keys[j], s->ordered.get() + first[j] * length_, s->indices.get() + first[j],
              out->sizes[j], &out->encoded[j]);
    });
    if (out->held) out->local.assign(s->indices.get(), s->indices.get() + first[nodes]);
    pool_.Give(std::move(s));
  }

  ScratchPool* pool() { return &pool_; }

 private:
  // The bucket's own subtree, level by level, as the rules of copc_octree.h split it.
  void BuildLevels(const Bucket& b, size_t left, bool parallel, Builder* builder,
                   BucketNodes* out) {
    std::vector<Range> level{{KeyOf(b.level, b.code), 0, b.size(), left}};
    while (!level.empty()) {
      // Cells narrower than a LAS unit: only duplicates share one; keep them all here.
      const int depth = level[0].key.level;
      const bool keep_all =
          std::ldexp(tree_.spacing, -depth) < min_scale_ || depth + kCellBits >= kFixedBits;
      if (!keep_all && depth + kCellBits > builder->base() + kKeyLevels) {
        builder->Rebase(level, parallel);
      }
      const size_t first = out->keys.size();
      CANDI_CHECK(first + level.size() < size_t{kAbove}) << "COPC bucket of too many nodes";
      for (const Range& r : level) out->keys.push_back(r.key);
      out->sizes.resize(out->keys.size(), 0);
      // Large nodes one at a time, each on every thread; the small ones a thread each.
      std::vector<std::vector<Range>> children(level.size());
      std::vector<size_t> small;
      for (size_t j = 0; j < level.size(); ++j) {
        if (parallel && level[j].end - level[j].begin > kLargeNodePoints) {
          out->sizes[first + j] = builder->Split(level[j], static_cast<uint32_t>(first + j),
                                                 keep_all, true, &children[j]);
        } else {
          small.push_back(j);
        }
      }
      Loop(parallel, small.size(), [&](size_t k) {
        const size_t j = small[k];
        out->sizes[first + j] = builder->Split(level[j], static_cast<uint32_t>(first + j), keep_all,
                                               false, &children[j]);
      });
      std::vector<Range> next;
      for (const std::vector<Range>& c : children) next.insert(next.end(), c.begin(), c.end());
      std::sort(next.begin(), next.end(), [](const Range& x, const Range& y) {
        return std::tie(x.key.x, x.key.y, x.key.z) < std::tie(y.key.x, y.key.y, y.key.z);
      });
      level = std::move(next);
    }
  }

  // The bucket's records in node order (each node's in input order) into s.ordered, their
  // indices into s.indices; the points kept above into out->above.
  void Gather(const Bucket& b, const Scratch& s, BucketNodes* out) const {
    const size_t m = b.size(), nodes = out->keys.size();
    std::vector<size_t> next(nodes + 1, 0);
    for (size_t j = 0; j < nodes; ++j) next[j + 1] = next[j] + out->sizes[j];
    const uint32_t* index = list_ + b.begin;
    for (size_t j = 0; j < m; ++j) {
      const uint32_t id = s.node_of[j];
      if (id >= kAbove) {
        const int k = static_cast<int>(id - kAbove);
        out->above.push_back(uint64_t{AboveIndex(k, AncestorCode(b, k))} << 32 | index[j]);
        continue;
      }
      const size_t at = next[id]++;
      std::memcpy(s.ordered.get() + at * length_, s.records.get() + j * length_, length_);
      s.indices[at] = index[j];
    }
  }

  template <typename F>
  static void Loop(bool parallel, size_t n, const F& f) {
    if (parallel) {
      ParallelFor(size_t{0}, n, f);
    } else {
      for (size_t i = 0; i < n; ++i) f(i);
    }
  }

  const CopcOctreeOptions& options_;
  const uint8_t* const records_;
  const size_t length_;
  const Cube cube_;
  const CopcOctree& tree_;
  const double min_scale_;
  const uint32_t* const list_;
  const CopcNodeEncoder& encode_;
  Sorter sort_;
  ScratchPool pool_;
};

// The rules at the nodes above the buckets, from the points reaching each (over all buckets):
// fold[i] is the node that takes the points reaching node i when i's subtree (fewer than
// min_subtree_points: i itself) or i's octant (fewer than min_octant_points: its parent) folds,
// kNone otherwise; nodes inside a folded one are not visited.
std::vector<uint32_t> FoldsAbove(const CopcOctreeOptions& options,
                                 const std::vector<uint64_t>& reached,
                                 const std::vector<uint8_t>& above) {
  std::vector<uint32_t> fold(kAboveNodes, kNone);
  std::vector<uint8_t> inside(kAboveNodes, 0);
  for (int level = 0; level < kBucketLevel; ++level) {
    for (uint32_t code = 0; code < (uint32_t{1} << (3 * level)); ++code) {
      const uint32_t i = AboveIndex(level, code);
      if (!above[i] || reached[i] == 0) continue;
      if (level > 0) {
        const uint32_t parent = AboveIndex(level - 1, code >> 3);
        if (inside[parent] || fold[parent] != kNone) {
          inside[i] = 1;
          continue;
        }
      }
      if (fold[i] != kNone) continue;  // its octant folds into its parent
      if (reached[i] < static_cast<uint64_t>(options.min_subtree_points)) {
        fold[i] = i;
        continue;
      }
      if (level + 1 >= kBucketLevel) continue;
      for (uint32_t o = 0; o < 8; ++o) {
        const uint32_t child = AboveIndex(level + 1, code << 3 | o);
        if (above[child] && reached[child] > 0 &&
            reached[child] < static_cast<uint64_t>(options.min_octant_points)) {
          fold[child] = i;
        }
      }
    }
  }
  return fold;
}

// The nodes above the buckets (their points: `above`, sorted), encoded by parallel batches and
// handed on level by level, each level in Morton order.
void EncodeAbove(const CopcOctreeOptions& options, const uint8_t* records, size_t length,
                 const std::vector<uint64_t>& above, const CopcNodeEncoder& encode,
                 ScratchPool* pool,
                 const std::function<void(const CopcKey&, uint64_t, std::vector<uint8_t>*)>& sink) {
  struct Group {
    uint32_t node;
    size_t begin, end;
  };
  std::vector<Group> groups;
  for (size_t a = 0; a < above.size();) {
    const uint32_t node = static_cast<uint32_t>(above[a] >> 32);
    size_t b = a;
    while (b < above.size() && static_cast<uint32_t>(above[b] >> 32) == node) ++b;
    groups.push_back({node, a, b});
    a = b;
  }
  std::vector<std::vector<uint8_t>> encoded;
  for (size_t first = 0, count = 0; first < groups.size(); first += count) {
    size_t points = 0;
    for (count = 0; first + count < groups.size() && points < options.batch_points; ++count) {
      points += groups[first + count].end - groups[first + count].begin;
    }
    encoded.assign(count, {});
    ParallelFor(size_t{0}, count, [&](size_t j) {
      const Group& g = groups[first + j];
      const size_t m = g.end - g.begin;
      std::unique_ptr<Scratch> s = pool->Take();
      s->Reserve(m, length);
      for (size_t k = 0; k < m; ++k) {
        const uint32_t i = static_cast<uint32_t>(above[g.begin + k]);
        s->indices[k] = i;
        std::memcpy(s->ordered.get() + k * length, records + size_t{i} * length, length);
      }
      const int level = LevelOfIndex(g.node);
      encode(KeyOf(level, g.node - LevelStart(level)), s->ordered.get(), s->indices.get(), m,
             &encoded[j]);
      pool->Give(std::move(s));
    });
    for (size_t j = 0; j < count; ++j) {
      const Group& g = groups[first + j];
      const int level = LevelOfIndex(g.node);
      sink(KeyOf(level, g.node - LevelStart(level)), g.end - g.begin, &encoded[j]);
    }
  }
}

}  // namespace

CopcOctree BuildCopcNodes(const CopcOctreeOptions& options, const uint8_t* records, size_t n,
                          size_t record_length, const Eigen::Vector3d& scale,
                          const Eigen::Vector3d& offset, const CopcXyzBounds* xyz_bounds,
                          const CopcNodeEncoder& encode, const CopcNodeSink& sink,
                          const std::function<void(uint64_t, uint64_t)>& bucketing,
                          const std::function<void(uint64_t, uint64_t)>& encoding) {
  options.Check();
  CANDI_CHECK(n <= size_t{std::numeric_limits<uint32_t>::max()})
      << "a COPC octree of " << n << " points (at most 2^32 - 1)";
  CopcOctree tree;
  const Cube cube = RecordsCube(records, n, record_length, scale, offset, xyz_bounds, &tree);
  if (n == 0) return tree;
  const double min_scale = scale.cwiseAbs().minCoeff();
  if (bucketing) bucketing(0, n);
  const std::unique_ptr<uint32_t[]> list(new uint32_t[n]);
  const int deepest = DeepestBucketLevel(tree, min_scale);
  std::vector<Bucket> buckets;
  if (n <= options.bucket_points || deepest == 0) {
    buckets.push_back({0, 0, 0, n});
    std::iota(list.get(), list.get() + n, uint32_t{0});
  } else {
    buckets = CutBuckets(records, n, record_length, cube, options.bucket_points, deepest,
                         list.get(), bucketing);
  }
  if (bucketing) bucketing(n, n);

  auto hand_on = [&](const CopcKey& key, uint64_t count, std::vector<uint8_t>* encoded) {
    tree.nodes.push_back({key, count, {}});
    sink(key, count, encoded);
  };
  NodeBuilder builder(options, records, record_length, cube, tree, min_scale, list.get(), encode);
  // What the rules above the buckets need: the points reaching each node above one, and which
  // nodes are above one.
  std::vector<uint64_t> reached(kAboveNodes, 0);
  std::vector<uint8_t> is_above(kAboveNodes, 0);
  std::vector<uint64_t> above;  // AboveIndex << 32 | point index
  std::vector<std::pair<size_t, BucketNodes>> held;
  std::vector<uint8_t> was_held(buckets.size(), 0);
  uint64_t settled = 0;
  if (encoding) encoding(0, n);
  std::vector<BucketNodes> built;
  for (size_t first = 0, count = 0; first < buckets.size(); first += count) {
    size_t points = 0;
    for (count = 0; first + count < buckets.size() && points < options.batch_points; ++count) {
      points += buckets[first + count].size();
    }
    built.assign(count, {});
    ParallelFor(size_t{0}, count, [&](size_t j) { builder.Build(buckets[first + j], &built[j]); });
    for (size_t j = 0; j < count; ++j) {
      const Bucket& b = buckets[first + j];
      BucketNodes& nodes = built[j];
      uint64_t reaching = b.size();
      for (int k = 0; k < b.level; ++k) {
        const uint32_t i = AboveIndex(k, AncestorCode(b, k));
        is_above[i] = 1;
        reached[i] += reaching;
        reaching -= nodes.kept[k];
      }
      if (nodes.held) {
        was_held[first + j] = 1;
        held.emplace_back(first + j, std::move(nodes));
        continue;
      }
      for (size_t k = 0; k < nodes.keys.size(); ++k) {
        hand_on(nodes.keys[k], nodes.sizes[k], &nodes.encoded[k]);
        settled += nodes.sizes[k];
      }
      above.insert(above.end(), nodes.above.begin(), nodes.above.end());
    }
    built.clear();
    if (encoding) encoding(settled, n);
  }
  // The rules above the buckets. Only a held bucket can lie in a node that folds.
  const std::vector<uint32_t> fold = FoldsAbove(options, reached, is_above);
  auto folded_at = [&](const Bucket& b) {  // the outermost level above b that folds, or -1
    for (int k = 0; k < b.level; ++k) {
      if (fold[AboveIndex(k, AncestorCode(b, k))] != kNone) return k;
    }
    return -1;
  };
  for (size_t j = 0; j < buckets.size(); ++j) {
    CANDI_CHECK(was_held[j] || folded_at(buckets[j]) < 0)
        << "COPC bucket " << j << " written before a node above it folded";
  }
  for (auto& [j, nodes] : held) {
    const Bucket& b = buckets[j];
    const int k = folded_at(b);
    if (k < 0) {
      for (size_t i = 0; i < nodes.keys.size(); ++i) {
        hand_on(nodes.keys[i], nodes.sizes[i], &nodes.encoded[i]);
        settled += nodes.sizes[i];
      }
      above.insert(above.end(), nodes.above.begin(), nodes.above.end());
      continue;
    }
    // Every point of the bucket reaching level k goes to the node its fold names.
    const uint64_t to = uint64_t{fold[AboveIndex(k, AncestorCode(b, k))]} << 32;
    for (uint64_t a : nodes.above) {
      const bool higher = LevelOfIndex(static_cast<uint32_t>(a >> 32)) < k;
      above.push_back(higher ? a : to | (a & 0xFFFFFFFFu));
    }
    for (uint32_t i : nodes.local) above.push_back(to | i);
  }
  if (encoding) encoding(settled, n);
  held.clear();
  tbb::parallel_sort(above.begin(), above.end());  // distinct values: one order on any threads
  EncodeAbove(options, records, record_length, above, encode, builder.pool(),
              [&](const CopcKey& key, uint64_t count, std::vector<uint8_t>* encoded) {
                hand_on(key, count, encoded);
                settled += count;
                if (encoding) encoding(settled, n);
              });
  CANDI_CHECK_EQ(settled, uint64_t{n}) << "COPC octree points";
  return tree;
}

CopcOctree BuildCopcOctree(const CopcOctreeOptions& options, const uint8_t* records, size_t n,
                           size_t record_length, const Eigen::Vector3d& scale,
                           const Eigen::Vector3d& offset, const CopcXyzBounds* xyz_bounds) {
  std::vector<std::vector<uint64_t>> points;
  CopcOctree tree = BuildCopcNodes(
      options, records, n, record_length, scale, offset, xyz_bounds,
      [](const CopcKey&, const uint8_t*, const uint32_t* indices, size_t count,
         std::vector<uint8_t>* out) {
        out->resize(count * sizeof(uint32_t));
        std::memcpy(out->data(), indices, out->size());
      },
      [&](const CopcKey&, uint64_t count, std::vector<uint8_t>* encoded) {
        std::vector<uint64_t>& p = points.emplace_back(count);
        for (uint64_t k = 0; k < count; ++k) {
          uint32_t i;
          std::memcpy(&i, encoded->data() + 4 * k, 4);
          p[k] = i;
        }
      });
  for (size_t j = 0; j < tree.nodes.size(); ++j) tree.nodes[j].points = std::move(points[j]);
  std::sort(tree.nodes.begin(), tree.nodes.end(), [](const CopcNode& a, const CopcNode& b) {
    return std::tie(a.key.level, a.key.x, a.key.y, a.key.z) <
           std::tie(b.key.level, b.key.x, b.key.y, b.key.z);
  });
  return tree;
}

}  // namespace candi::io

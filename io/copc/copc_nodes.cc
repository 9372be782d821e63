// The bucket pipeline of io/copc/copc_octree.h: the cube cut into buckets by the counts of its
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
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "core/binary_file.h"
#include "core/check.h"
#include "core/parallel.h"
#include "core/spill_file.h"
#include "io/copc/copc_buckets_internal.h"
#include "io/copc/copc_octree.h"
#include "io/copc/copc_octree_internal.h"

namespace candi::io {

namespace {

using namespace copc_internal;

// node_of of a point that a node above its bucket keeps, at level k: kAbove + k.
constexpr uint32_t kAbove = 0xFFFFFF00u;

// A bucket's working memory (its points' elements and nodes, its records in node order), kept
// from bucket to bucket; a pool hands each bucket in the works its own.
struct Scratch {
  std::unique_ptr<uint8_t[]> ordered;
  std::unique_ptr<Element[]> elements;
  std::unique_ptr<uint32_t[]> node_of, indices, at;  // at: where in the group each record is
  size_t capacity = 0, record_bytes = 0;
  void Reserve(size_t points, size_t length) {
    if (points > capacity) {
      capacity = std::max(points, capacity + capacity / 2);
      elements.reset(new Element[capacity]);
      node_of.reset(new uint32_t[capacity]);
      indices.reset(new uint32_t[capacity]);
      at.reset(new uint32_t[capacity]);
    }
    if (points * length > record_bytes) {
      record_bytes = std::max(points * length, record_bytes + record_bytes / 2);
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

// A point that a node above the buckets keeps (or may yet take): key = the node's AboveIndex <<
// 32 | the point's index (in input order); `at`, where its record is (an index into the group's
// records while its bucket is built, then into the records the nodes above are read from).
struct AboveEntry {
  uint64_t key;
  uint64_t at;
  bool operator<(const AboveEntry& o) const { return key < o.key; }
};

// A bucket built: its own nodes (level by level, each level by (x, y, z)) encoded, the points
// that nodes above it keep, and what the rules above need.
struct BucketNodes {
  std::vector<CopcKey> keys;
  std::vector<uint64_t> sizes;
  std::vector<std::vector<uint8_t>> encoded;
  std::vector<AboveEntry> above;              // each point kept above
  std::array<uint64_t, kBucketLevel> kept{};  // points kept at each level above the bucket
  // Held: a node above may yet fold the bucket's points into itself; then its nodes' points
  // (key: the point's index alone, in node order) go there too.
  bool held = false;
  std::vector<AboveEntry> local;
};

// Buckets of at least this many points are built on several threads.
constexpr size_t kParallelBucket = size_t{1} << 20;

class NodeBuilder {
 public:
  NodeBuilder(const CopcOctreeOptions& options, size_t length, const Cube& cube,
              const CopcOctree& tree, double min_scale, const CopcNodeEncoder& encode)
      : options_(options),
        length_(length),
        cube_(cube),
        tree_(tree),
        min_scale_(min_scale),
        encode_(encode),
        sort_(options.sort_scratch_points) {}

  // The group of buckets built next: its records, its buckets' lists (indices into records) and
  // each record's index in input order (null: the records are all n, in input order).
  void SetGroup(const uint8_t* records, const uint32_t* list, const uint32_t* global) {
    records_ = records;
    list_ = list;
    global_ = global;
  }

  // Builds bucket `b` into *out; on several threads when it is large or `alone` (the only one
  // in the works).
  void Build(const Bucket& b, bool alone, BucketNodes* out) {
    std::unique_ptr<Scratch> s = pool_.Take();
    const size_t m = b.size();
    const bool parallel = alone || m >= kParallelBucket;
    s->Reserve(m, length_);
    const uint32_t* index = list_ + b.begin;
    Loop(parallel, (m + kBlock - 1) / kBlock, [&](size_t block) {
      for (size_t j = block * kBlock; j < std::min(m, (block + 1) * kBlock); ++j) {
        if (j + 16 < m) __builtin_prefetch(records_ + size_t{index[j + 16]} * length_);
        Element& e = s->elements[j];
        LoadXyz(records_ + size_t{index[j]} * length_, e.xyz);
        e.key = MortonCode(cube_(e.xyz), 0);
        e.index = static_cast<uint32_t>(j);
      }
    });
    // The bucket's keys share the octants of the levels down to its own.
    sort_(s->elements.get(), m, 3 * (kKeyLevels - b.level));
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
    if (out->held) {
      out->local.resize(first[nodes]);
      for (size_t j = 0; j < first[nodes]; ++j) out->local[j] = {s->indices[j], s->at[j]};
    }
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
      const uint32_t id = s.node_of[j], i = global_ ? global_[index[j]] : index[j];
      if (id >= kAbove) {
        const int k = static_cast<int>(id - kAbove);
        out->above.push_back({uint64_t{AboveIndex(k, AncestorCode(b, k))} << 32 | i, index[j]});
        continue;
      }
      const size_t at = next[id]++;
      CopyRecord(s.ordered.get() + at * length_, records_ + size_t{index[j]} * length_, length_);
      s.indices[at] = i;
      s.at[at] = index[j];
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
  const size_t length_;
  const Cube cube_;
  const CopcOctree& tree_;
  const double min_scale_;
  const CopcNodeEncoder& encode_;
  const uint8_t* records_ = nullptr;
  const uint32_t *list_ = nullptr, *global_ = nullptr;
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

// The nodes above the buckets (their points: `above`, sorted; a point's record at records + at *
// length), encoded by parallel batches and handed on level by level, each level in Morton order.
void EncodeAbove(const CopcOctreeOptions& options, const uint8_t* records, size_t length,
                 const std::vector<AboveEntry>& above, const CopcNodeEncoder& encode,
                 ScratchPool* pool,
                 const std::function<void(const CopcKey&, uint64_t, std::vector<uint8_t>*)>& sink) {
  struct Group {
    uint32_t node;
    size_t begin, end;
  };
  std::vector<Group> groups;
  for (size_t a = 0; a < above.size();) {
    const uint32_t node = static_cast<uint32_t>(above[a].key >> 32);
    size_t b = a;
    while (b < above.size() && static_cast<uint32_t>(above[b].key >> 32) == node) ++b;
    groups.push_back({node, a, b});
    a = b;
  }
  auto key_of = [](uint32_t node) {
    const int level = LevelOfIndex(node);
    return KeyOf(level, node - LevelStart(level));
  };
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
        const AboveEntry& e = above[g.begin + k];
        s->indices[k] = static_cast<uint32_t>(e.key);
        CopyRecord(s->ordered.get() + k * length, records + e.at * length, length);
      }
      encode(key_of(g.node), s->ordered.get(), s->indices.get(), m, &encoded[j]);
      pool->Give(std::move(s));
    });
    for (size_t j = 0; j < count; ++j) {
      const Group& g = groups[first + j];
      sink(key_of(g.node), g.end - g.begin, &encoded[j]);
    }
  }
}

// The build, by groups of consecutive buckets (one of all of them when the records are in
// memory): each group's buckets built in parallel batches and handed on in order, except those
// held; then the rules above the buckets, the held buckets, and the nodes above.
class Pipeline {
 public:
  Pipeline(const CopcOctreeOptions& options, size_t length, const Cube& cube, CopcOctree* tree,
           double min_scale, const CopcNodeEncoder& encode, const CopcNodeSink& sink,
           const std::function<void(uint64_t, uint64_t)>& encoding, size_t n)
      : options_(options),
        length_(length),
        tree_(tree),
        encode_(encode),
        sink_(sink),
        encoding_(encoding),
        n_(n),
        builder_(options, length, cube, *tree, min_scale, encode),
        reached_(kAboveNodes, 0),
        is_above_(kAboveNodes, 0) {}

  // Builds buckets[0, count) of a group (records, list and global as NodeBuilder::SetGroup).
  // store: where the records of points the nodes above keep, or may take, are copied (null: they
  // are read where they are at the end, `records` being all n in input order).
  void Group(const uint8_t* records, const uint32_t* list, const uint32_t* global,
             const Bucket* buckets, size_t count, SpillFile* store) {
    builder_.SetGroup(records, list, global);
    if (encoding_) encoding_(settled_, n_);
    // Each batch's nodes are handed on (by one task) while the next batch is built: in order,
    // and by one thread at a time, as when they were handed on between the batches.
    std::vector<BucketNodes> built, built_last;
    size_t first_last = 0;
    auto hand_on_last = [&] {
      for (size_t j = 0; j < built_last.size(); ++j) {
        Take(buckets[first_last + j], &built_last[j], records, store);
      }
      built_last.clear();
    };
    for (size_t first = 0, batch = 0; first < count; first += batch) {
      size_t points = 0;
      for (batch = 0; first + batch < count && points < options_.batch_points; ++batch) {
        points += buckets[first + batch].size();
      }
      built.assign(batch, {});
      const size_t tasks = built_last.empty() ? 0 : 1;
      ParallelFor(size_t{0}, tasks + batch, [&](size_t j) {
        if (j < tasks) return hand_on_last();
        builder_.Build(buckets[first + j - tasks], batch == 1, &built[j - tasks]);
      });
      if (encoding_) encoding_(settled_, n_);
      std::swap(built, built_last);
      first_last = first;
    }
    hand_on_last();
    if (encoding_) encoding_(settled_, n_);
  }

  // The rules above the buckets, the held buckets, then the nodes above (their records at
  // records + at * length).
  void Finish(const uint8_t* records) {
    const std::vector<uint32_t> fold = FoldsAbove(options_, reached_, is_above_);
    auto folded_at = [&](const Bucket& b) {  // the outermost level above b that folds, or -1
      for (int k = 0; k < b.level; ++k) {
        if (fold[AboveIndex(k, AncestorCode(b, k))] != kNone) return k;
      }
      return -1;
    };
    for (const Bucket& b : written_) {
      CANDI_CHECK(folded_at(b) < 0)
          << "COPC bucket " << b.level << "-" << b.code << " written before a node above it folded";
    }
    for (auto& [b, nodes] : held_) {
      const int k = folded_at(b);
      if (k < 0) {
        HandOn(&nodes);
        continue;
      }
      // Every point of the bucket reaching level k goes to the node its fold names.
      const uint64_t to = uint64_t{fold[AboveIndex(k, AncestorCode(b, k))]} << 32;
      for (const AboveEntry& e : nodes.above) {
        const bool higher = LevelOfIndex(static_cast<uint32_t>(e.key >> 32)) < k;
        above_.push_back(higher ? e : AboveEntry{to | (e.key & 0xFFFFFFFFu), e.at});
      }
      for (const AboveEntry& e : nodes.local) above_.push_back({to | e.key, e.at});
    }
    held_.clear();
    if (encoding_) encoding_(settled_, n_);
    // Distinct keys: one order on any thread count.
    tbb::parallel_sort(above_.begin(), above_.end());
    EncodeAbove(options_, records, length_, above_, encode_, builder_.pool(),
                [&](const CopcKey& key, uint64_t count, std::vector<uint8_t>* encoded) {
                  tree_->nodes.push_back({key, count, {}});
                  sink_(key, count, encoded);
                  settled_ += count;
                  if (encoding_) encoding_(settled_, n_);
                });
    CANDI_CHECK_EQ(settled_, uint64_t{n_}) << "COPC octree points";
  }

 private:
  // A bucket built: its counts into the rules above; its nodes handed on, or the whole held.
  void Take(const Bucket& b, BucketNodes* nodes, const uint8_t* records, SpillFile* store) {
    uint64_t reaching = b.size();
    for (int k = 0; k < b.level; ++k) {
      const uint32_t i = AboveIndex(k, AncestorCode(b, k));
      is_above_[i] = 1;
      reached_[i] += reaching;
      reaching -= nodes->kept[k];
    }
    Store(&nodes->above, records, store);
    if (nodes->held) {
      Store(&nodes->local, records, store);
      held_.emplace_back(b, std::move(*nodes));
      return;
    }
    written_.push_back(b);
    HandOn(nodes);
  }

  void HandOn(BucketNodes* nodes) {
    for (size_t k = 0; k < nodes->keys.size(); ++k) {
      tree_->nodes.push_back({nodes->keys[k], nodes->sizes[k], {}});
      sink_(nodes->keys[k], nodes->sizes[k], &nodes->encoded[k]);
      settled_ += nodes->sizes[k];
    }
    above_.insert(above_.end(), nodes->above.begin(), nodes->above.end());
  }

  // The entries' records copied to the store (their `at` then where they are in it).
  void Store(std::vector<AboveEntry>* entries, const uint8_t* records, SpillFile* store) {
    if (!store) return;
    std::vector<uint8_t> copied(entries->size() * length_);
    for (size_t k = 0; k < entries->size(); ++k) {
      AboveEntry& e = (*entries)[k];
      CopyRecord(copied.data() + k * length_, records + e.at * length_, length_);
      e.at = store->size() / length_ + k;
    }
    store->Append(copied.data(), copied.size());
  }

  const CopcOctreeOptions& options_;
  const size_t length_;
  CopcOctree* const tree_;
  const CopcNodeEncoder& encode_;
  const CopcNodeSink& sink_;
  const std::function<void(uint64_t, uint64_t)>& encoding_;
  const size_t n_;
  NodeBuilder builder_;
  // What the rules above the buckets need: the points reaching each node above one, and which
  // nodes are above one.
  std::vector<uint64_t> reached_;
  std::vector<uint8_t> is_above_;
  std::vector<AboveEntry> above_;
  std::vector<std::pair<Bucket, BucketNodes>> held_;
  std::vector<Bucket> written_;
  uint64_t settled_ = 0;
};

}  // namespace

CopcOctree BuildCopcNodes(const CopcOctreeOptions& options, const CopcRecords& input,
                          const Eigen::Vector3d& scale, const Eigen::Vector3d& offset,
                          const CopcXyzBounds* xyz_bounds, const CopcNodeEncoder& encode,
                          const CopcNodeSink& sink,
                          const std::function<void(uint64_t, uint64_t)>& bucketing,
                          const std::function<void(uint64_t, uint64_t)>& encoding) {
  options.Check();
  const size_t n = input.n, length = input.record_length;
  CANDI_CHECK(n <= size_t{std::numeric_limits<uint32_t>::max()})
      << "a COPC octree of " << n << " points (at most 2^32 - 1)";
  CANDI_CHECK(length >= 12) << "COPC records of " << length << " bytes (X, Y, Z take 12)";
  CANDI_CHECK((input.data != nullptr) != (input.spill != nullptr) || n == 0)
      << "COPC records: in memory or spilled";
  CopcOctree tree;
  CANDI_CHECK(!input.spill || input.spill->size() == uint64_t{n} * length) << "COPC spill size";
  // A spill's bounds, when not given, from a pass over its runs.
  CopcXyzBounds spill_bounds;
  if (input.spill && !xyz_bounds && n > 0) {
    spill_bounds[0].fill(std::numeric_limits<int32_t>::max());
    spill_bounds[1].fill(std::numeric_limits<int32_t>::min());
    SpillRuns runs(input.spill, length, /*discard=*/false);
    const uint8_t* run;
    size_t first, m;
    while (runs.Next(&run, &first, &m)) {
      for (size_t i = 0; i < m; ++i) {
        int32_t xyz[3];
        LoadXyz(run + i * length, xyz);
        for (int k = 0; k < 3; ++k) {
          spill_bounds[0][k] = std::min(spill_bounds[0][k], xyz[k]);
          spill_bounds[1][k] = std::max(spill_bounds[1][k], xyz[k]);
        }
      }
    }
    xyz_bounds = &spill_bounds;
  }
  const uint8_t* all = input.data;
  const Cube cube = RecordsCube(all, n, length, scale, offset, xyz_bounds, &tree);
  if (n == 0) return tree;
  const double min_scale = scale.cwiseAbs().minCoeff();
  const int deepest = DeepestBucketLevel(tree, min_scale);
  if (bucketing) bucketing(0, n);
  Pipeline pipeline(options, length, cube, &tree, min_scale, encode, sink, encoding, n);
  if (!input.spill) {
    const std::unique_ptr<uint32_t[]> list(new uint32_t[n]);
    std::vector<Bucket> buckets;
    if (n <= options.bucket_points || deepest == 0) {
      buckets.push_back({0, 0, 0, n});
      std::iota(list.get(), list.get() + n, uint32_t{0});
    } else {
      const std::unique_ptr<uint32_t[]> cells(new uint32_t[n]);
      std::vector<uint32_t> bucket_of;
      CellCounter counter(cube);
      counter.Add(all, n, length, cells.get());
      buckets = ChooseBuckets(counter.Counts(), options.bucket_points, deepest, &bucket_of);
      if (bucketing) bucketing(n / 2, n);
      ListByBucket(cells.get(), n, bucket_of, 0, buckets.size(), buckets.data(), list.get());
    }
    if (bucketing) bucketing(n, n);
    pipeline.Group(all, list.get(), nullptr, buckets.data(), buckets.size(), nullptr);
    pipeline.Finish(all);
    return tree;
  }
  // Spilled: the buckets from every cell's count, then group by group from files of their own.
  CANDI_CHECK(input.memory_points > 0 && !input.spill_dir.empty()) << "COPC spill: no memory";
  std::vector<uint32_t> bucket_of;
  std::vector<Bucket> buckets;
  {
    CellCounter counter(cube);
    SpillRuns runs(input.spill, length, /*discard=*/false);
    const uint8_t* run;
    size_t first, m;
    while (runs.Next(&run, &first, &m)) counter.Add(run, m, length, nullptr);
    buckets = ChooseBuckets(counter.Counts(), options.bucket_points, deepest, &bucket_of);
  }
  if (bucketing) bucketing(n / 3, n);
  std::vector<GroupFiles> groups = RouteToGroups(input.spill, length, cube, buckets, bucket_of,
                                                 input.memory_points, input.spill_dir);
  if (bucketing) bucketing(n, n);
  SpillFile above(input.spill_dir + "/above.records");
  for (GroupFiles& g : groups) {
    const SpillFile::Mapping records = g.records->Map(), indices = g.indices->Map();
    const size_t m = records.size() / length;
    std::unique_ptr<uint32_t[]> list(new uint32_t[m]);
    {
      const std::unique_ptr<uint32_t[]> cells(new uint32_t[m]);
      ParallelFor(size_t{0}, (m + kBlock - 1) / kBlock, [&](size_t b) {
        for (size_t i = b * kBlock; i < std::min(m, (b + 1) * kBlock); ++i) {
          cells[i] = CellOf(records.data() + i * length, cube);
        }
      });
      ListByBucket(cells.get(), m, bucket_of, g.first, g.count, buckets.data() + g.first,
                   list.get());
    }
    pipeline.Group(records.data(), list.get(), reinterpret_cast<const uint32_t*>(indices.data()),
                   buckets.data() + g.first, g.count, &above);
    g.records.reset();
    g.indices.reset();
  }
  const SpillFile::Mapping above_records = above.Map();
  pipeline.Finish(above_records.data());
  return tree;
}

CopcOctree BuildCopcNodes(const CopcOctreeOptions& options, const uint8_t* records, size_t n,
                          size_t record_length, const Eigen::Vector3d& scale,
                          const Eigen::Vector3d& offset, const CopcXyzBounds* xyz_bounds,
                          const CopcNodeEncoder& encode, const CopcNodeSink& sink,
                          const std::function<void(uint64_t, uint64_t)>& bucketing,
                          const std::function<void(uint64_t, uint64_t)>& encoding) {
  CopcRecords input;
  input.data = records;
  input.n = n;
  input.record_length = record_length;
  return BuildCopcNodes(options, input, scale, offset, xyz_bounds, encode, sink, bucketing,
                        encoding);
}

CopcOctree BuildCopcOctree(const CopcOctreeOptions& options, const CopcRecords& input,
                           const Eigen::Vector3d& scale, const Eigen::Vector3d& offset,
                           const CopcXyzBounds* xyz_bounds) {
  std::vector<std::vector<uint64_t>> points;
  CopcOctree tree = BuildCopcNodes(
      options, input, scale, offset, xyz_bounds,
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

CopcOctree BuildCopcOctree(const CopcOctreeOptions& options, const uint8_t* records, size_t n,
                           size_t record_length, const Eigen::Vector3d& scale,
                           const Eigen::Vector3d& offset, const CopcXyzBounds* xyz_bounds) {
  CopcRecords input;
  input.data = records;
  input.n = n;
  input.record_length = record_length;
  return BuildCopcOctree(options, input, scale, offset, xyz_bounds);
}

}  // namespace candi::io

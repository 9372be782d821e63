#include "io/las/copc_octree.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <memory>
#include <limits>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <tbb/enumerable_thread_specific.h>

#include "core/binary_file.h"
#include "core/check.h"
#include "core/morton.h"
#include "core/parallel.h"

namespace candi::io {

namespace {

constexpr int kCellBits = 7;  // 128 = 2^7 cells a side
static_assert(1 << kCellBits == kCopcCellsPerAxis);

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

uint64_t Code(const Element& e) { return e.key & ~kKept; }

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
uint64_t MortonCode(const Place& q, int base) {
  const int shift = kFixedBits - base - kKeyLevels;
  auto bits = [&](int k) { return shift >= 0 ? q[k] >> shift : q[k] << -shift; };
  return MortonCode21(bits(0), bits(1), bits(2));
}

// Squared distance (float bits, which order as the values do for >= 0) above the index: the
// smaller of two is the nearer point, the earlier on a tie.
uint64_t Packed(double distance, uint32_t index) {
  const float d = static_cast<float>(distance);
  uint32_t bits;
  std::memcpy(&bits, &d, 4);
  return uint64_t{bits} << 32 | index;
}

// Sorts elements by Code, most significant 9 bits first (bits [0, top) unsorted, the ones above
// equal): by a scatter through `scratch` where it holds the range, else by cycles in place.
constexpr int kDigitBits = 9;
constexpr size_t kSmallSort = 32;

void InsertionSort(Element* a, size_t n) {
  for (size_t i = 1; i < n; ++i) {
    const Element e = a[i];
    size_t j = i;
    for (; j > 0 && Code(a[j - 1]) > Code(e); --j) a[j] = a[j - 1];
    a[j] = e;
  }
}

void SortElements(Element* a, size_t n, int top, std::vector<Element>* scratch,
                  size_t scratch_cap) {
  constexpr size_t kDigits = size_t{1} << kDigitBits;
  while (n > kSmallSort && top > 0) {
    const int shift = std::max(0, top - kDigitBits);
    const uint64_t mask = (uint64_t{1} << (top - shift)) - 1;
    auto digit = [&](const Element& e) { return (Code(e) >> shift) & mask; };
    std::array<size_t, kDigits + 1> begin{};
    for (size_t i = 0; i < n; ++i) ++begin[digit(a[i]) + 1];
    if (*std::max_element(begin.begin(), begin.end()) == n) {  // one bucket: the next digit
      top = shift;
      continue;
    }
    for (size_t u = 0; u < kDigits; ++u) begin[u + 1] += begin[u];
    std::array<size_t, kDigits> next;
    std::copy(begin.begin(), begin.end() - 1, next.begin());
    if (n <= scratch_cap) {
      if (scratch->size() < n) {
        scratch->resize(std::min(scratch_cap, std::max(n, 2 * scratch->size())));
      }
      Element* s = scratch->data();
      for (size_t i = 0; i < n; ++i) s[next[digit(a[i])]++] = a[i];
      std::copy(s, s + n, a);
    } else {
      for (size_t u = 0; u < kDigits; ++u) {
        while (next[u] < begin[u + 1]) {
          Element e = a[next[u]];
          for (uint64_t d = digit(e); d != u; d = digit(e)) std::swap(e, a[next[d]++]);
          a[next[u]++] = e;
        }
      }
    }
    for (size_t u = 0; u < kDigits; ++u) {
      if (begin[u + 1] - begin[u] > 1) {
        SortElements(a + begin[u], begin[u + 1] - begin[u], shift, scratch, scratch_cap);
      }
    }
    return;
  }
  InsertionSort(a, n);
}

// The sorts of one build: each thread's scratch, of at most `cap` elements, freed with it.
class Sorter {
 public:
  explicit Sorter(size_t cap) : cap_(cap) {}
  void operator()(Element* a, size_t n, int top) {
    SortElements(a, n, top, &scratch_.local(), cap_);
  }

 private:
  const size_t cap_;
  tbb::enumerable_thread_specific<std::vector<Element>> scratch_;
};

constexpr size_t kBlock = size_t{1} << 16;  // points a task takes

// The points' cube (into tree) and their elements in Morton order (into elements[0, n)), with
// `codes` (n) for their codes on the way: the bounds by parallel blocks (a minimum and a maximum
// do not depend on the order), the codes and their counts by the first 12 bits, the elements
// scattered by them, each bucket sorted on.
// The world bounds of the records' positions, X * scale + offset (by parallel blocks), or from
// their integer bounds when known: the position is a monotonic function of the integer, so its
// extremes are those of the integer's.
void WorldBounds(const uint8_t* records, size_t n, size_t length, const Eigen::Vector3d& scale,
                 const Eigen::Vector3d& offset, const CopcXyzBounds* xyz_bounds,
                 Eigen::Vector3d* lo_out, Eigen::Vector3d* hi_out) {
  auto world = [&](const int32_t* p) {
    return Eigen::Vector3d(p[0] * scale[0] + offset[0], p[1] * scale[1] + offset[1],
                           p[2] * scale[2] + offset[2]);
  };
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(INFINITY), hi = -lo;
  if (n == 0) {
    lo = hi = Eigen::Vector3d::Zero();
  } else if (xyz_bounds) {
    const Eigen::Vector3d a = world((*xyz_bounds)[0].data()), b = world((*xyz_bounds)[1].data());
    lo = a.cwiseMin(b);
    hi = a.cwiseMax(b);
  } else {
    const size_t blocks = (n + kBlock - 1) / kBlock;
    std::vector<Eigen::Vector3d> block_lo(blocks), block_hi(blocks);
    ParallelFor(size_t{0}, blocks, [&](size_t b) {
      Eigen::Vector3d block_min = Eigen::Vector3d::Constant(INFINITY), block_max = -block_min;
      for (size_t i = b * kBlock; i < std::min(n, (b + 1) * kBlock); ++i) {
        int32_t p[3];
        for (int k = 0; k < 3; ++k) p[k] = LoadLE<int32_t>(records + i * length + 4 * k);
        const Eigen::Vector3d w = world(p);
        block_min = block_min.cwiseMin(w);
        block_max = block_max.cwiseMax(w);
      }
      block_lo[b] = block_min;
      block_hi[b] = block_max;
    });
    for (size_t b = 0; b < blocks; ++b) {
      lo = lo.cwiseMin(block_lo[b]);
      hi = hi.cwiseMax(block_hi[b]);
    }
  }
  *lo_out = lo;
  *hi_out = hi;
}

void SortedElements(const uint8_t* records, size_t n, size_t length, const Eigen::Vector3d& scale,
                    const Eigen::Vector3d& offset, const CopcXyzBounds* xyz_bounds, Sorter* sort,
                    CopcOctree* tree, Cube* cube, Element* elements, uint64_t* codes) {
  const size_t blocks = (n + kBlock - 1) / kBlock;
  auto block_end = [&](size_t b) { return std::min(n, (b + 1) * kBlock); };
  auto xyz = [&](size_t i, int32_t* out) {
    for (int k = 0; k < 3; ++k) out[k] = LoadLE<int32_t>(records + i * length + 4 * k);
  };
  Eigen::Vector3d lo, hi;
  WorldBounds(records, n, length, scale, offset, xyz_bounds, &lo, &hi);
  tree->center = 0.5 * (lo + hi);
  tree->halfsize = 0.5 * (hi - lo).maxCoeff();
  if (!(tree->halfsize > 0.0)) tree->halfsize = scale.cwiseAbs().maxCoeff();
  tree->spacing = 2.0 * tree->halfsize / kCopcCellsPerAxis;
  *cube = {scale, offset, tree->center.array() - tree->halfsize, 2.0 * tree->halfsize};
  if (n == 0) return;

  constexpr int kFirstBits = 12;
  constexpr size_t kFirst = size_t{1} << kFirstBits;
  constexpr int kFirstShift = 3 * kKeyLevels - kFirstBits;
  std::vector<uint32_t> counts(blocks * kFirst, 0);
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    uint32_t* count = counts.data() + b * kFirst;
    for (size_t i = b * kBlock; i < block_end(b); ++i) {
      int32_t p[3];
      xyz(i, p);
      codes[i] = MortonCode((*cube)(p), 0);
      ++count[codes[i] >> kFirstShift];
    }
  });
  std::vector<size_t> bucket_begin(kFirst + 1);
  size_t at = 0;
  for (size_t u = 0; u < kFirst; ++u) {
    bucket_begin[u] = at;
    for (size_t b = 0; b < blocks; ++b) {
      const uint32_t c = counts[b * kFirst + u];
      counts[b * kFirst + u] = static_cast<uint32_t>(at);
      at += c;
    }
  }
  bucket_begin[kFirst] = at;
  ParallelFor(size_t{0}, blocks, [&](size_t b) {
    uint32_t* next = counts.data() + b * kFirst;
    for (size_t i = b * kBlock; i < block_end(b); ++i) {
      Element& e = elements[next[codes[i] >> kFirstShift]++];
      e.key = codes[i];
      xyz(i, e.xyz);
      e.index = static_cast<uint32_t>(i);
    }
  });
  ParallelFor(size_t{0}, kFirst, [&](size_t u) {
    (*sort)(elements + bucket_begin[u], bucket_begin[u + 1] - bucket_begin[u], kFirstShift);
  });
}

// The least squared distance from a cell's centre (in cell widths, as float bits) of a point in
// each of its 8^3 subcells, three levels down, by their octants' bits (a Morton code: the
// nearest level highest, x, y, z the low bits of each). Along an axis the three bits b1 b2 b3
// place the point at [v / 8, (v + 1) / 8), v = 4 b1 + 2 b2 + b3, at least m / 8 from the
// centre, m = 3 - v when b1 = 0 and v - 4 when b1 = 1.
constexpr int kBoundLevels = 3;
struct SubcellBound {
  uint32_t bits[512];
  SubcellBound() {
    for (uint32_t code = 0; code < 512; ++code) {
      int sum = 0;
      for (int k = 0; k < 3; ++k) {
        const int v = static_cast<int>(((code >> (6 + k)) & 1) << 2 | ((code >> (3 + k)) & 1) << 1 |
                                       ((code >> k) & 1));
        const int m = v < 4 ? 3 - v : v - 4;
        sum += m * m;
      }
      const float bound = static_cast<float>(sum) / 64.0f;
      std::memcpy(&bits[code], &bound, 4);
    }
  }
};
const SubcellBound kSubcellBound;

// Runs f(0..n-1) on several threads or on this one.
template <typename F>
void Loop(bool parallel, size_t n, const F& f) {
  if (parallel) {
    ParallelFor(size_t{0}, n, f);
  } else {
    for (size_t i = 0; i < n; ++i) f(i);
  }
}

// A node being built: its points are the elements [begin, end) not yet kept, `size` of them.
struct Range {
  CopcKey key;
  size_t begin = 0, end = 0, size = 0;
};

CopcKey ChildKey(const CopcKey& key, int octant) {
  return {key.level + 1, 2 * key.x + (octant & 1), 2 * key.y + ((octant >> 1) & 1),
          2 * key.z + ((octant >> 2) & 1)};
}

// Nodes of more points than this are split by several threads; smaller ones by one each.
constexpr size_t kLargeNodePoints = size_t{1} << 16;

// The tree's points, in Morton order by the keys of level `base`: a node keeps the nearest
// point of each of its cells (a run of its range) and passes the others on, in place, to the
// children that are the ranges of its octants.
class Builder {
 public:
  Builder(const CopcOctreeOptions& options, const Cube& cube, Sorter* sort, Element* elements,
          uint32_t* node_of)
      : options_(options), cube_(cube), sort_(sort), elements_(elements), node_of_(node_of) {}

  int base() const { return base_; }

  // Re-keys the points of `ranges` (one level's nodes) by the keys of their own level.
  void Rebase(const std::vector<Range>& ranges) {
    base_ = ranges[0].key.level;
    auto rekey = [&](size_t i) {
      Element& e = elements_[i];
      e.key = (e.key & kKept) | MortonCode(cube_(e.xyz), base_);
    };
    for (const Range& r : ranges) {
      const bool large = r.end - r.begin > kLargeNodePoints;
      const size_t blocks = (r.end - r.begin + kBlock - 1) / kBlock;
      Loop(large, blocks, [&](size_t b) {
        const size_t end = std::min(r.end, r.begin + (b + 1) * kBlock);
        for (size_t i = r.begin + b * kBlock; i < end; ++i) rekey(i);
      });
    }
    ParallelFor(size_t{0}, ranges.size(), [&](size_t j) {
      (*sort_)(elements_ + ranges[j].begin, ranges[j].end - ranges[j].begin, 3 * kKeyLevels);
    });
  }

  // Splits node `range` (id `id`): its points one a cell, the rest to its children (into
  // children, octant order); its points' node_of set to id; returns how many it keeps.
  size_t Split(const Range& range, uint32_t id, bool keep_all, bool parallel,
               std::vector<Range>* children) {
    const int level = range.key.level;
    if (keep_all || range.size < static_cast<size_t>(options_.min_subtree_points)) {
      KeepAll(range.begin, range.end, id, parallel);
      return range.size;
    }
    // The node's octants (one level down) and cells (kCellBits down) are runs of its codes.
    const int octant_shift = 3 * (base_ + kKeyLevels - (level + 1));
    const int cell_shift = 3 * (base_ + kKeyLevels - (level + kCellBits));
    std::array<size_t, 9> octant_begin;
    for (int o = 0; o < 8; ++o) {
      octant_begin[o] = static_cast<size_t>(
          std::partition_point(elements_ + range.begin, elements_ + range.end,
                               [&](const Element& e) {
                                 return static_cast<int>((Code(e) >> octant_shift) & 7) < o;
                               }) -
          elements_);
    }
    octant_begin[8] = range.end;
    // Blocks of whole cells, each kept nearest point counted by octant.
    std::vector<size_t> cuts{range.begin};
    if (parallel) {
      const size_t blocks = (range.end - range.begin + kBlock - 1) / kBlock;
      for (size_t b = 1; b < blocks; ++b) {
        const size_t at = std::max(cuts.back(), range.begin + b * kBlock);
        if (at >= range.end) break;
        const uint64_t cell = Code(elements_[at - 1]) >> cell_shift;
        cuts.push_back(static_cast<size_t>(
            std::partition_point(elements_ + at, elements_ + range.end,
                                 [&](const Element& e) { return Code(e) >> cell_shift == cell; }) -
            elements_));
      }
    }
    cuts.push_back(range.end);
    std::vector<std::array<size_t, 8>> passed_in(cuts.size() - 1);
    Loop(parallel, cuts.size() - 1, [&](size_t b) {
      passed_in[b] = KeepNearest(cuts[b], cuts[b + 1], level, cell_shift, octant_shift, id);
    });
    size_t size = range.size;
    for (int o = 0; o < 8; ++o) {
      size_t passed = 0;
      for (const auto& p : passed_in) passed += p[o];
      if (passed == 0) continue;
      if (passed < static_cast<size_t>(options_.min_octant_points)) {
        KeepAll(octant_begin[o], octant_begin[o + 1], id, parallel);
        continue;
      }
      children->push_back({ChildKey(range.key, o), octant_begin[o], octant_begin[o + 1], passed});
      size -= passed;
    }
    return size;
  }

 private:
  // Keeps the nearest point of each cell in [begin, end) (whole cells); returns how many points
  // of each octant it passes on.
  std::array<size_t, 8> KeepNearest(size_t begin, size_t end, int level, int cell_shift,
                                    int octant_shift, uint32_t id) {
    const int place_shift = kFixedBits - (level + kCellBits);
    const uint64_t frac_mask = (uint64_t{1} << place_shift) - 1;
    const double frac_unit = std::ldexp(1.0, -place_shift);
    std::array<size_t, 8> passed{};
    auto keep = [&](size_t i) {
      Element& e = elements_[i];
      --passed[(e.key >> octant_shift) & 7];
      e.key |= kKept;
      node_of_[e.index] = id;
    };
    auto packed = [&](const Element& e) {
      const Place q = cube_(e.xyz);
      double distance = 0.0;
      for (int k = 0; k < 3; ++k) {
        const double f = static_cast<double>(q[k] & frac_mask) * frac_unit - 0.5;
        distance += f * f;
      }
      return Packed(distance, e.index);
    };
    // A bound from the key: the octants of the next three levels place a point in one of the
    // cell's 8^3 subcells, at least kSubcellBound from its centre; a point whose bound exceeds
    // the best distance is not computed. (A computed distance is never below its bound: the
    // subcells' faces are exact binary fractions and each rounding on the way is monotonic.)
    const int bound_levels = base_ + kKeyLevels - (level + kCellBits);
    const bool bounded = bound_levels >= kBoundLevels;
    const int bound_shift = bounded ? 3 * (bound_levels - kBoundLevels) : 0;
    auto subcell = [&](uint64_t key) { return (key >> bound_shift) & 511; };
    size_t i = begin;
    while (i < end) {
      if (elements_[i].key & kKept) {
        ++i;
        continue;
      }
      // The cell [cell_begin, i). First pass: the point of least bound (the first of them).
      const uint64_t cell = elements_[i].key >> cell_shift;
      const size_t cell_begin = i;
      uint32_t least = ~uint32_t{0};
      size_t best_at = i, live = 0;
      for (; i < end; ++i) {
        const uint64_t key = elements_[i].key;
        if (key & kKept) continue;
        if (key >> cell_shift != cell) break;
        ++live;
        const uint32_t bound = bounded ? kSubcellBound.bits[subcell(key)] : 0;
        if (bound < least) {
          least = bound;
          best_at = i;
        }
      }
      // Second pass: the best distance, from that point's.
      if (live > 1) {
        uint64_t best = packed(elements_[best_at]);
        for (size_t j = cell_begin; j < i; ++j) {
          const uint64_t key = elements_[j].key;
          if ((key & kKept) || j == best_at) continue;
          if (bounded && (uint64_t{kSubcellBound.bits[subcell(key)]} << 32) > best) continue;
          const uint64_t p = packed(elements_[j]);
          if (p < best) {
            best = p;
            best_at = j;
          }
        }
      }
      passed[(elements_[best_at].key >> octant_shift) & 7] += live;
      keep(best_at);
    }
    return passed;
  }

  // Keeps every point of [begin, end) not yet kept.
  void KeepAll(size_t begin, size_t end, uint32_t id, bool parallel) {
    const size_t blocks = (end - begin + kBlock - 1) / kBlock;
    Loop(parallel, blocks, [&](size_t b) {
      for (size_t i = begin + b * kBlock; i < std::min(end, begin + (b + 1) * kBlock); ++i) {
        Element& e = elements_[i];
        if (e.key & kKept) continue;
        e.key |= kKept;
        node_of_[e.index] = id;
      }
    });
  }

  const CopcOctreeOptions& options_;
  const Cube cube_;
  Sorter* const sort_;
  Element* const elements_;
  uint32_t* const node_of_;
  int base_ = 0;
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
                                  const std::function<void(uint64_t, uint64_t)>& progress,
                                  const CopcXyzBounds* xyz_bounds) {
  options.Check();
  CANDI_CHECK(n <= size_t{std::numeric_limits<uint32_t>::max()})
      << "a COPC octree of " << n << " points (at most 2^32 - 1)";
  CopcPartition partition;
  CopcOctree& tree = partition.tree;
  // Not value-initialised: the passes write every byte they read.
  partition.memory_bytes = std::max(n * (sizeof(Element) + sizeof(uint64_t)), n * record_length);
  partition.memory.reset(new uint8_t[partition.memory_bytes]);
  static_assert(alignof(Element) <= alignof(std::max_align_t));
  Element* elements = reinterpret_cast<Element*>(partition.memory.get());
  Cube cube;
  Sorter sort(options.sort_scratch_points);
  SortedElements(records, n, record_length, scale, offset, xyz_bounds, &sort, &tree, &cube,
                 elements, reinterpret_cast<uint64_t*>(elements + n));
  if (n == 0) return partition;
  partition.node_of.reset(new uint32_t[n]);
  Builder builder(options, cube, &sort, elements, partition.node_of.get());
  const double min_scale = scale.cwiseAbs().minCoeff();
  std::vector<Range> level{{CopcKey{}, 0, n, n}};
  uint64_t settled = 0;
  if (progress) progress(0, n);
  while (!level.empty()) {
    // Cells narrower than a LAS unit: only duplicates share one; keep them all here.
    const int depth = level[0].key.level;
    const bool keep_all =
        std::ldexp(tree.spacing, -depth) < min_scale || depth + kCellBits >= kFixedBits;
    if (!keep_all && depth + kCellBits > builder.base() + kKeyLevels) builder.Rebase(level);
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

// The octree machinery of io/copc/copc_octree.h over points in Morton order (declared in
// copc_octree_internal.h): the cube, the sort, and the builder that splits a node's range into its
// kept points and its children's ranges. The bucket pipeline that runs it is copc_nodes.cc.
#include "io/copc/copc_octree.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/binary_file.h"
#include "core/parallel.h"
#include "io/copc/copc_octree_internal.h"

namespace candi::io {

namespace copc_internal {

namespace {

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

}  // namespace

void Sorter::operator()(Element* a, size_t n, int top) {
  SortElements(a, n, top, &scratch_.local(), cap_);
}

namespace {

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

}  // namespace

Cube RecordsCube(const uint8_t* records, size_t n, size_t length, const Eigen::Vector3d& scale,
                 const Eigen::Vector3d& offset, const CopcXyzBounds* xyz_bounds, CopcOctree* tree) {
  Eigen::Vector3d lo, hi;
  WorldBounds(records, n, length, scale, offset, xyz_bounds, &lo, &hi);
  tree->center = 0.5 * (lo + hi);
  tree->halfsize = 0.5 * (hi - lo).maxCoeff();
  if (!(tree->halfsize > 0.0)) tree->halfsize = scale.cwiseAbs().maxCoeff();
  tree->spacing = 2.0 * tree->halfsize / kCopcCellsPerAxis;
  return {scale, offset, tree->center.array() - tree->halfsize, 2.0 * tree->halfsize};
}

void Builder::Rebase(const std::vector<Range>& ranges, bool parallel) {
  base_ = ranges[0].key.level;
  auto rekey = [&](size_t i) {
    Element& e = elements_[i];
    e.key = (e.key & kKept) | MortonCode(cube_(e.xyz), base_);
  };
  for (const Range& r : ranges) {
    const bool large = parallel && r.end - r.begin > kLargeNodePoints;
    const size_t blocks = (r.end - r.begin + kBlock - 1) / kBlock;
    Loop(large, blocks, [&](size_t b) {
      const size_t end = std::min(r.end, r.begin + (b + 1) * kBlock);
      for (size_t i = r.begin + b * kBlock; i < end; ++i) rekey(i);
    });
  }
  Loop(parallel, ranges.size(), [&](size_t j) {
    (*sort_)(elements_ + ranges[j].begin, ranges[j].end - ranges[j].begin, 3 * kKeyLevels);
  });
}

size_t Builder::Split(const Range& range, uint32_t id, bool keep_all, bool parallel,
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
        std::partition_point(
            elements_ + range.begin, elements_ + range.end,
            [&](const Element& e) { return static_cast<int>((Code(e) >> octant_shift) & 7) < o; }) -
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

size_t Builder::KeepNearestOfCells(const Range& range, uint32_t id) {
  const int level = range.key.level;
  const int octant_shift = 3 * (base_ + kKeyLevels - (level + 1));
  const int cell_shift = 3 * (base_ + kKeyLevels - (level + kCellBits));
  const std::array<size_t, 8> passed =
      KeepNearest(range.begin, range.end, level, cell_shift, octant_shift, id);
  size_t all = 0;
  for (size_t p : passed) all += p;
  return all;
}

std::array<size_t, 8> Builder::KeepNearest(size_t begin, size_t end, int level, int cell_shift,
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

void Builder::KeepAll(size_t begin, size_t end, uint32_t id, bool parallel) {
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

}  // namespace copc_internal

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
  if (bucket_points < 1) throw std::invalid_argument("CopcOctreeOptions::bucket_points = 0");
  if (batch_points < 1) throw std::invalid_argument("CopcOctreeOptions::batch_points = 0");
}

}  // namespace candi::io

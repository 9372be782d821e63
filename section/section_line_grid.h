// The cell grid of the section-line stages (section_lines_internal.h), private to them: items
// bucketed by square cells through an open-addressing table, and the points so bucketed in cells
// of the fit window's size. Include only from section/section_line*.cc and their tests.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

#include "core/rng.h"

namespace candi::section::lines_internal {

constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
constexpr uint64_t kEmptyKey = ~uint64_t{0};
constexpr int64_t kMaxCells = (int64_t{1} << 31) - 2;  // cells along an axis

// Cells: open addressing with linear probing, cell key -> value. Keys are never kEmptyKey.
class CellTable {
 public:
  // The value stored for `key`, storing `value` first if there is none.
  uint32_t FindOrInsert(uint64_t key, uint32_t value) {
    if (2 * (size_ + 1) > keys_.size()) Grow();
    size_t slot = Slot(key);
    for (; keys_[slot] != kEmptyKey; slot = (slot + 1) & (keys_.size() - 1)) {
      if (keys_[slot] == key) return values_[slot];
    }
    keys_[slot] = key;
    values_[slot] = value;
    ++size_;
    return value;
  }
  // kNone when absent.
  uint32_t Find(uint64_t key) const {
    if (keys_.empty()) return kNone;
    for (size_t slot = Slot(key);; slot = (slot + 1) & (keys_.size() - 1)) {
      if (keys_[slot] == key) return values_[slot];
      if (keys_[slot] == kEmptyKey) return kNone;
    }
  }
  // Replaces every value v by map[v].
  void Renumber(const std::vector<uint32_t>& map) {
    for (size_t slot = 0; slot < keys_.size(); ++slot) {
      if (keys_[slot] != kEmptyKey) values_[slot] = map[values_[slot]];
    }
  }

 private:
  size_t Slot(uint64_t key) const { return Mix64(key) & (keys_.size() - 1); }
  void Grow() {
    std::vector<uint64_t> keys = std::move(keys_);
    std::vector<uint32_t> values = std::move(values_);
    keys_.assign(std::max<size_t>(64, 2 * keys.size()), kEmptyKey);
    values_.assign(keys_.size(), 0);
    size_ = 0;
    for (size_t slot = 0; slot < keys.size(); ++slot) {
      if (keys[slot] != kEmptyKey) FindOrInsert(keys[slot], values[slot]);
    }
  }

  std::vector<uint64_t> keys_;
  std::vector<uint32_t> values_;
  size_t size_ = 0;
};

// Cell indices are offset by one so that the cells around a point at the grid's edge have keys.
inline uint64_t CellKey(const Eigen::Vector2d& p, double cell, int64_t dx = 0, int64_t dy = 0) {
  auto index = [&](double x, int64_t d) {
    const double i = std::clamp(std::floor(x / cell), -1.0, static_cast<double>(kMaxCells));
    return static_cast<uint64_t>(static_cast<int64_t>(i) + 1 + d);
  };
  return (index(p.x(), dx) << 32) | index(p.y(), dy);
}

// Items bucketed by square cells, cells in key order, items of a cell in index order.
struct Buckets {
  double cell = 1.0;
  CellTable table;              // cell key -> cell rank
  std::vector<uint32_t> start;  // first slot of each cell, by rank; then the end
  std::vector<uint32_t> items;  // item indices, grouped by cell

  // Calls f(slot) for every slot of the 3 x 3 cells around p (a superset of the items within
  // `cell` of p).
  template <typename F>
  void ForEachNear(const Eigen::Vector2d& p, const F& f) const {
    for (int64_t dx = -1; dx <= 1; ++dx) {
      for (int64_t dy = -1; dy <= 1; ++dy) {
        const uint32_t c = table.Find(CellKey(p, cell, dx, dy));
        if (c == kNone) continue;
        for (uint32_t slot = start[c]; slot < start[c + 1]; ++slot) f(slot);
      }
    }
  }
};

// Buckets items 0..n-1 at positions get(i, &p) (false: skip the item).
template <typename Get>
Buckets BuildBuckets(size_t n, double cell, const Get& get) {
  Buckets b;
  b.cell = cell;
  std::vector<uint32_t> cell_of(n, kNone), counts;
  std::vector<uint64_t> keys;
  Eigen::Vector2d p;
  for (size_t i = 0; i < n; ++i) {
    if (!get(i, &p)) continue;
    const uint64_t key = CellKey(p, cell);
    const uint32_t id = b.table.FindOrInsert(key, static_cast<uint32_t>(keys.size()));
    if (id == keys.size()) {
      keys.push_back(key);
      counts.push_back(0);
    }
    ++counts[id];
    cell_of[i] = id;
  }
  std::vector<uint32_t> order(keys.size()), rank(keys.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) { return keys[x] < keys[y]; });
  b.start.assign(keys.size() + 1, 0);
  for (uint32_t r = 0; r < order.size(); ++r) {
    rank[order[r]] = r;
    b.start[r + 1] = b.start[r] + counts[order[r]];
  }
  b.table.Renumber(rank);
  std::vector<uint32_t> cursor(b.start.begin(), b.start.end() - 1);
  b.items.resize(b.start.back());
  for (size_t i = 0; i < n; ++i) {
    if (cell_of[i] != kNone) b.items[cursor[rank[cell_of[i]]]++] = static_cast<uint32_t>(i);
  }
  return b;
}

// The points, relative to the origin, bucketed in cells of the fit window's size; within a cell
// sorted by (u, v), so that the work of the stages does not depend on the input order.
struct PointGrid {
  Buckets buckets;
  std::vector<Eigen::Vector2d> points;  // by slot
};

// The finite points of `input`, minus `origin`, in cells of side `cell`.
PointGrid BuildPointGrid(const std::vector<Eigen::Vector2d>& input, const Eigen::Vector2d& origin,
                         double cell);

}  // namespace candi::section::lines_internal

// Stage 3 of the section lines (section_lines_internal.h): links between the vertices, the
// minimum spanning forest of the links, and its split into paths.
#include "section/section_lines_internal.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

namespace candi::section::lines_internal {

namespace {

// Continuation links: within 15 degrees of the tangent (a chord of length d on a curve of radius
// R turns by d / 2R: R >= 2d; a continuation across to a parallel curve h away needs d >= 3.7 h),
// tangents within 30 degrees (kCosTangents); the cost of sideways offsets.
constexpr double kTanNarrow = 0.26794919243112270;    // tan 15 degrees
constexpr double kAcrossPenalty = 4.0;

// Links are searched side by side: side 0 of a vertex is ahead (along +t), side 1 behind.
class Linker {
 public:
  Linker(const std::vector<Vertex>& v, const Context& ctx)
      : v_(v),
        max_gap_(ctx.max_gap),
        search_(ctx.max_gap + 2 * ctx.scales.radius),
        abeam_(0.25 * ctx.spacing),
        buckets_(BuildBuckets(v.size(), search_,
                              [&](size_t i, Eigen::Vector2d* p) {
                                *p = v[i].p;
                                return true;
                              })),
        next_(2 * v.size(), kNone),
        end_(2 * v.size(), kNone) {}

  // First the continuations: each side links to the neighbour within 15 degrees of the tangent
  // (and it within 15 degrees of its own), with a tangent within 30 degrees, of least
  // along + 4 across. Then the ends (sides with none) are matched in pairs, the pairs whose
  // curves end nearest each other first: the two arms of a corner, not the parallel face of a
  // wall nor the middle of a curve.
  std::vector<Edge> Link() {
    for (uint32_t a = 0; a < v_.size(); ++a) Continuations(a);
    MatchEnds();
    std::vector<Edge> edges;
    for (uint32_t a = 0; a < v_.size(); ++a) {
      for (uint32_t side = 2 * a; side < 2 * a + 2; ++side) {
        uint32_t b = next_[side];
        if (b == kNone && end_[side] != kNone) b = end_[side] / 2;
        if (b != kNone)
          edges.push_back({std::min(a, b), std::max(a, b), (v_[b].p - v_[a].p).norm()});
      }
    }
    std::sort(edges.begin(), edges.end(), EdgeLess);
    edges.erase(std::unique(edges.begin(), edges.end(),
                            [](const Edge& x, const Edge& y) { return x.a == y.a && x.b == y.b; }),
                edges.end());
    return edges;
  }

  static bool EdgeLess(const Edge& x, const Edge& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; }

 private:
  // Whether the data gap between a and b, on their sides sa and sb, is at most max_gap.
  bool Near(uint32_t a, int sa, uint32_t b, int sb, double d) const {
    return d > 0 && d <= search_ && d - v_[a].reach[sa] - v_[b].reach[sb] <= max_gap_;
  }

  void Continuations(uint32_t a) {
    double best_cost[2] = {0, 0};
    buckets_.ForEachNear(v_[a].p, [&](uint32_t slot) {
      const uint32_t b = buckets_.items[slot];
      const Eigen::Vector2d rel = v_[b].p - v_[a].p;
      const double along = v_[a].t.dot(rel), across = std::abs(Cross(v_[a].t, rel));
      const int s = along > 0 ? 0 : 1, sb = v_[b].t.dot(rel) < 0 ? 0 : 1;
      if (b == a || !Near(a, s, b, sb, rel.norm())) return;
      // Within the cone of each tangent (a smooth curve's chord makes about the same angle with
      // both), the tangents alike.
      if (across > kTanNarrow * std::abs(along)) return;
      if (std::abs(Cross(v_[b].t, rel)) > kTanNarrow * std::abs(v_[b].t.dot(rel))) return;
      if (std::abs(v_[a].t.dot(v_[b].t)) < kCosTangents) return;
      const double cost = std::abs(along) + kAcrossPenalty * across;
      if (next_[2 * a + s] == kNone || cost < best_cost[s])
        next_[2 * a + s] = b, best_cost[s] = cost;
    });
  }

  // The end side of a (no continuation) that a vertex in direction `toward` may join: the side
  // it lies on, or the other one when it is nearly abeam; -1 if none.
  int EndSide(uint32_t a, const Eigen::Vector2d& toward) const {
    const double along = v_[a].t.dot(toward);
    const int s = along > 0 ? 0 : 1;
    if (next_[2 * a + s] == kNone) return s;
    if (std::abs(along) <= abeam_ && next_[2 * a + 1 - s] == kNone) return 1 - s;
    return -1;
  }

  // Where the curve seen by vertex a ends on side s.
  Eigen::Vector2d ReachEnd(uint32_t a, int s) const {
    return v_[a].p + (s == 0 ? 1.0 : -1.0) * v_[a].reach[s] * v_[a].t;
  }

  struct EndPair {
    double cost;
    uint32_t side_a, side_b;  // side_a < side_b
    bool operator<(const EndPair& o) const {
      if (cost != o.cost) return cost < o.cost;
      return side_a != o.side_a ? side_a < o.side_a : side_b < o.side_b;
    }
  };

  // The end sides that could join a's end sides, with their cost.
  void EndPairs(uint32_t a, std::vector<EndPair>* pairs) const {
    if (next_[2 * a] != kNone && next_[2 * a + 1] != kNone) return;
    buckets_.ForEachNear(v_[a].p, [&](uint32_t slot) {
      const uint32_t b = buckets_.items[slot];
      const Eigen::Vector2d rel = v_[b].p - v_[a].p;
      const int sa = EndSide(a, rel), sb = EndSide(b, -rel);
      if (b <= a || sa < 0 || sb < 0 || !Near(a, sa, b, sb, rel.norm())) return;
      const double cost = (ReachEnd(b, sb) - ReachEnd(a, sa)).norm();
      pairs->push_back({cost, 2 * a + sa, 2 * b + sb});
    });
  }

  // Greedy matching of the end sides, cheapest pair first.
  void MatchEnds() {
    std::vector<EndPair> pairs;
    for (uint32_t a = 0; a < v_.size(); ++a) EndPairs(a, &pairs);
    std::sort(pairs.begin(), pairs.end());
    for (const EndPair& pair : pairs) {
      if (end_[pair.side_a] != kNone || end_[pair.side_b] != kNone) continue;
      end_[pair.side_a] = pair.side_b;
      end_[pair.side_b] = pair.side_a;
    }
  }

  const std::vector<Vertex>& v_;
  double max_gap_, search_, abeam_;
  Buckets buckets_;
  std::vector<uint32_t> next_;  // by side (2 a + s): the continuation vertex, or kNone
  std::vector<uint32_t> end_;   // by end side: the end side matched to it, or kNone
};

uint32_t Find(std::vector<uint32_t>& parent, uint32_t x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

// The last alive neighbour of `cur` (in adjacency order) other than `prev`, or kNone.
uint32_t NextOnChain(const Forest& f, uint32_t cur, uint32_t prev) {
  uint32_t step = kNone;
  for (uint32_t k = f.offset[cur]; k < f.offset[cur + 1]; ++k) {
    if (f.alive[f.next[k]] && f.next[k] != prev) step = f.next[k];
  }
  return step;
}

class PathSplitter {
 public:
  PathSplitter(const std::vector<Vertex>& v, const Forest& f)
      : v_(v), f_(f), used_(v.size(), 0), dist_(v.size(), 0), parent_(v.size(), kNone) {}

  // Each tree: its longest path, then the leftover branches, each from the vertex it hangs on.
  std::vector<PathLine> Split() {
    std::vector<PathLine> lines;
    for (uint32_t s = 0; s < v_.size(); ++s) {
      if (!f_.alive[s] || used_[s]) continue;
      const std::vector<uint32_t> first = LongestFrom(s);
      lines.push_back({LongestFrom(first.back()), false});
      Claim(lines.back().ids);
      while (!tasks_.empty()) {
        const auto [root, start] = tasks_.back();
        tasks_.pop_back();
        if (used_[start]) continue;
        PathLine branch{{root}, true};
        const std::vector<uint32_t> rest = LongestFrom(start);
        branch.ids.insert(branch.ids.end(), rest.begin(), rest.end());
        lines.push_back(std::move(branch));
        Claim(rest);
      }
    }
    return lines;
  }

 private:
  // The path from `start` to the farthest unused vertex of its tree (ties: the lowest index).
  std::vector<uint32_t> LongestFrom(uint32_t start) {
    std::vector<uint32_t> stack{start};
    dist_[start] = 0;
    parent_[start] = kNone;
    uint32_t far = start;
    while (!stack.empty()) {
      const uint32_t x = stack.back();
      stack.pop_back();
      if (dist_[x] > dist_[far] || (dist_[x] == dist_[far] && x < far)) far = x;
      for (uint32_t k = f_.offset[x]; k < f_.offset[x + 1]; ++k) {
        const uint32_t y = f_.next[k];
        if (!f_.alive[y] || used_[y] || y == parent_[x]) continue;
        parent_[y] = x;
        dist_[y] = dist_[x] + (v_[y].p - v_[x].p).norm();
        stack.push_back(y);
      }
    }
    std::vector<uint32_t> path;
    for (uint32_t x = far; x != kNone; x = parent_[x]) path.push_back(x);
    std::reverse(path.begin(), path.end());
    return path;
  }

  void Claim(const std::vector<uint32_t>& path) {
    for (uint32_t x : path) used_[x] = 1;
    for (uint32_t x : path) {
      for (uint32_t k = f_.offset[x]; k < f_.offset[x + 1]; ++k) {
        const uint32_t y = f_.next[k];
        if (f_.alive[y] && !used_[y]) tasks_.emplace_back(x, y);
      }
    }
  }

  const std::vector<Vertex>& v_;
  const Forest& f_;
  std::vector<uint8_t> used_;
  std::vector<double> dist_;
  std::vector<uint32_t> parent_;
  std::vector<std::pair<uint32_t, uint32_t>> tasks_;  // (root on a line, first vertex off it)
};

}  // namespace

std::vector<Edge> LinkVertices(const std::vector<Vertex>& v, const Context& ctx) {
  return Linker(v, ctx).Link();
}

bool Linked(const std::vector<Edge>& edges, uint32_t a, uint32_t b) {
  const Edge key{std::min(a, b), std::max(a, b), 0};
  return std::binary_search(edges.begin(), edges.end(), key, Linker::EdgeLess);
}

// Kruskal: the shortest links that join different trees.
Forest SpanningForest(size_t n, std::vector<Edge> edges) {
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
    if (x.length != y.length) return x.length < y.length;
    return x.a != y.a ? x.a < y.a : x.b < y.b;
  });
  std::vector<uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  std::vector<Edge> kept, dropped;
  for (const Edge& e : edges) {
    const uint32_t ra = Find(parent, e.a), rb = Find(parent, e.b);
    if (ra == rb) {
      dropped.push_back(e);
      continue;
    }
    parent[ra] = rb;
    kept.push_back(e);
  }
  Forest f;
  std::vector<uint8_t> root_loop(n, 0);
  for (const Edge& e : dropped) root_loop[Find(parent, e.a)] = 1;
  f.loop.resize(n);
  for (uint32_t i = 0; i < n; ++i) f.loop[i] = root_loop[Find(parent, i)];
  f.offset.assign(n + 1, 0);
  for (const Edge& e : kept) ++f.offset[e.a + 1], ++f.offset[e.b + 1];
  for (size_t i = 0; i < n; ++i) f.offset[i + 1] += f.offset[i];
  f.next.resize(f.offset[n]);
  std::vector<uint32_t> cursor(f.offset.begin(), f.offset.end() - 1);
  for (const Edge& e : kept) f.next[cursor[e.a]++] = e.b, f.next[cursor[e.b]++] = e.a;
  f.alive.assign(n, 1);
  f.degree.resize(n);
  for (size_t i = 0; i < n; ++i) f.degree[i] = f.offset[i + 1] - f.offset[i];
  return f;
}

// Removes the spurs shorter than min_length: leaf-to-junction chains (a noisy corner or a stub
// of a few vertices), so that the longest paths run through the curves themselves.
void PruneSpurs(const std::vector<Vertex>& v, double min_length, Forest* f) {
  std::vector<uint32_t> chain;
  for (uint32_t leaf = 0; leaf < v.size(); ++leaf) {
    if (!f->alive[leaf] || f->degree[leaf] != 1) continue;
    chain.assign(1, leaf);
    uint32_t prev = kNone, cur = leaf;
    double length = 0;
    while (length < min_length) {
      const uint32_t step = NextOnChain(*f, cur, prev);
      if (step == kNone || f->degree[step] == 1) break;  // the whole tree is one path
      length += (v[step].p - v[cur].p).norm();
      if (f->degree[step] >= 3) {
        if (length < min_length) {
          for (uint32_t x : chain) f->alive[x] = 0;
          --f->degree[step];
        }
        break;
      }
      chain.push_back(step);
      prev = cur, cur = step;
    }
  }
}

std::vector<PathLine> SplitPaths(const std::vector<Vertex>& v, const Forest& f) {
  return PathSplitter(v, f).Split();
}

}  // namespace candi::section::lines_internal

#include "mesh/cad_section.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "core/check.h"
#include "core/text_format.h"

namespace candi::mesh {

namespace {

std::string Point(const Eigen::Vector2d& p) {
  return "(" + FormatDouble(p.x()) + ", " + FormatDouble(p.y()) + ")";
}

struct DisjointSets {
  explicit DisjointSets(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  size_t Find(size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  }
  void Join(size_t a, size_t b) { parent[Find(a)] = Find(b); }
  std::vector<size_t> parent;
};

// The open pieces' ends (end 2k = first point of piece k, 2k+1 = its last), clustered into nodes
// of ends closer than `tolerance`. Returns the node of each end, numbered 0.. in end order.
std::vector<size_t> ClusterEnds(const std::vector<Eigen::Vector2d>& ends, double tolerance) {
  std::vector<size_t> order(ends.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return ends[a].x() < ends[b].x(); });
  DisjointSets sets(ends.size());
  for (size_t i = 0; i < order.size(); ++i) {
    for (size_t j = i + 1; j < order.size(); ++j) {
      if (ends[order[j]].x() - ends[order[i]].x() > tolerance) break;
      if ((ends[order[j]] - ends[order[i]]).norm() <= tolerance) sets.Join(order[i], order[j]);
    }
  }
  std::vector<size_t> node(ends.size()), root_node(ends.size(), SIZE_MAX);
  size_t next = 0;
  for (size_t e = 0; e < ends.size(); ++e) {
    const size_t root = sets.Find(e);
    if (root_node[root] == SIZE_MAX) root_node[root] = next++;
    node[e] = root_node[root];
  }
  return node;
}

// Throws when pieces fall into more than one connected chain, naming the smallest gap between
// free ends of different chains.
void CheckConnected(const std::vector<Eigen::Vector2d>& ends, const std::vector<size_t>& node,
                    const std::vector<size_t>& degree, const SectionSource& source) {
  const size_t pieces = ends.size() / 2;
  DisjointSets chains(pieces);
  std::vector<size_t> piece_of_node(degree.size(), SIZE_MAX);
  for (size_t e = 0; e < ends.size(); ++e) {
    size_t& p = piece_of_node[node[e]];
    if (p == SIZE_MAX)
      p = e / 2;
    else
      chains.Join(p, e / 2);
  }
  size_t count = 0;
  for (size_t p = 0; p < pieces; ++p) count += chains.Find(p) == p;
  if (count <= 1) return;
  double gap = std::numeric_limits<double>::infinity();
  Eigen::Vector2d a = Eigen::Vector2d::Zero(), b = a;
  for (size_t i = 0; i < ends.size(); ++i) {
    if (degree[node[i]] != 1) continue;
    for (size_t j = i + 1; j < ends.size(); ++j) {
      if (degree[node[j]] != 1 || chains.Find(i / 2) == chains.Find(j / 2)) continue;
      const double d = (ends[i] - ends[j]).norm();
      if (d < gap) gap = d, a = ends[i], b = ends[j];
    }
  }
  std::string message = "the section falls into " + std::to_string(count) + " separate chains";
  if (std::isfinite(gap)) {
    message += "; the smallest gap is " + FormatDouble(gap) + " m, between " + Point(a) + " and " +
               Point(b) +
               " (pieces join when their ends are within the join "
               "tolerance)";
  }
  FailSection(source, message);
}

// Walks the chain from a free end (or around the loop), appending pieces in order.
Polyline2 WalkChain(const std::vector<Polyline2>& pieces, const std::vector<size_t>& node,
                    const std::vector<size_t>& degree) {
  std::vector<std::vector<size_t>> ends_at(degree.size());
  for (size_t e = 0; e < node.size(); ++e) ends_at[node[e]].push_back(e);
  size_t start = 0;  // end 0 when every node joins two ends (a loop)
  for (size_t e = 0; e < node.size(); ++e) {
    if (degree[node[e]] == 1) {
      start = e;
      break;
    }
  }
  Polyline2 chain;
  std::vector<bool> used(pieces.size(), false);
  size_t end = start;
  while (true) {
    const size_t piece = end / 2;
    used[piece] = true;
    std::vector<Eigen::Vector2d> pts = pieces[piece].points;
    if (end % 2 == 1) std::reverse(pts.begin(), pts.end());
    chain.points.insert(chain.points.end(), pts.begin() + (chain.points.empty() ? 0 : 1),
                        pts.end());
    const size_t at = node[end ^ 1];
    size_t next = SIZE_MAX;
    for (size_t e : ends_at[at]) {
      if (!used[e / 2]) next = e;
    }
    if (next == SIZE_MAX) {
      chain.closed = at == node[start] && pieces.size() > 1;
      if (chain.closed) chain.points.pop_back();
      return chain;
    }
    end = next;
  }
}

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

bool OnSegment(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return std::min(a.x(), b.x()) <= p.x() && p.x() <= std::max(a.x(), b.x()) &&
         std::min(a.y(), b.y()) <= p.y() && p.y() <= std::max(a.y(), b.y());
}

// Whether segments pq and rs share a point; *at receives one shared point.
bool SegmentsMeet(const Eigen::Vector2d& p, const Eigen::Vector2d& q, const Eigen::Vector2d& r,
                  const Eigen::Vector2d& s, Eigen::Vector2d* at) {
  const double d1 = Cross(q - p, r - p), d2 = Cross(q - p, s - p);
  const double d3 = Cross(s - r, p - r), d4 = Cross(s - r, q - r);
  if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) {
    *at = p + (q - p) * (d3 / (d3 - d4));
    return true;
  }
  const Eigen::Vector2d candidates[4] = {r, s, p, q};
  const bool hits[4] = {d1 == 0 && OnSegment(r, p, q), d2 == 0 && OnSegment(s, p, q),
                        d3 == 0 && OnSegment(p, r, s), d4 == 0 && OnSegment(q, r, s)};
  for (int k = 0; k < 4; ++k) {
    if (hits[k]) {
      *at = candidates[k];
      return true;
    }
  }
  return false;
}

// Adjacent segments ab, bc overlap beyond b when the line doubles back on itself.
bool DoublesBack(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  return Cross(b - a, c - b) == 0 && (b - a).dot(c - b) < 0;
}

}  // namespace

void FailSection(const SectionSource& source, const std::string& message) {
  throw InputError(source.path, "layer '" + source.layer + "'", message);
}

void SectionOptions::Check() const {
  CANDI_CHECK_OPTION(join_tolerance > 0 && std::isfinite(join_tolerance), join_tolerance,
                     "finite and > 0");
  CANDI_CHECK_OPTION(merge_tolerance >= 0 && std::isfinite(merge_tolerance), merge_tolerance,
                     "finite and >= 0");
}

Polyline2 MergeCoincidentVertices(const Polyline2& line, double tolerance) {
  Polyline2 out;
  out.closed = line.closed;
  for (const Eigen::Vector2d& p : line.points) {
    if (out.points.empty() || (p - out.points.back()).norm() > tolerance) out.points.push_back(p);
  }
  if (out.closed && out.points.size() > 1 &&
      (out.points.back() - out.points.front()).norm() <= tolerance) {
    out.points.pop_back();
  }
  return out;
}

Polyline2 AssembleSection(const SectionOptions& options, const std::vector<Polyline2>& pieces,
                          const SectionSource& source) {
  options.Check();
  if (pieces.empty())
    FailSection(source, "no section geometry (polyline, spline or lines) on the layer");
  Polyline2 chain;
  if (pieces.size() == 1) {
    chain = pieces[0];
  } else {
    std::vector<Eigen::Vector2d> ends;
    for (const Polyline2& piece : pieces) {
      if (piece.closed || piece.points.empty()) {
        FailSection(source, "a closed or empty piece among " + std::to_string(pieces.size()) +
                                " pieces: a section is one line");
      }
      ends.push_back(piece.points.front());
      ends.push_back(piece.points.back());
    }
    const std::vector<size_t> node = ClusterEnds(ends, options.join_tolerance);
    std::vector<size_t> degree(*std::max_element(node.begin(), node.end()) + 1, 0);
    for (size_t n : node) ++degree[n];
    for (size_t e = 0; e < ends.size(); ++e) {
      if (degree[node[e]] > 2) {
        FailSection(source, "the section branches at " + Point(ends[e]) + ": " +
                                std::to_string(degree[node[e]]) + " piece ends meet there");
      }
    }
    CheckConnected(ends, node, degree, source);
    chain = WalkChain(pieces, node, degree);
  }
  chain = MergeCoincidentVertices(chain, options.merge_tolerance);
  if (chain.points.size() < 3) {
    FailSection(source, "the section has " + std::to_string(chain.points.size()) +
                            " distinct vertices; at least 3 are needed");
  }
  const SelfIntersection cross = FindSelfIntersection(chain);
  if (cross.found) {
    FailSection(source, "the section crosses itself at " + Point(cross.point) + " (segments " +
                            std::to_string(cross.segment_a) + " and " +
                            std::to_string(cross.segment_b) + ")");
  }
  return chain;
}

SelfIntersection FindSelfIntersection(const Polyline2& line) {
  SelfIntersection result;
  const size_t n = line.points.size();
  const size_t segments = line.closed ? n : (n > 0 ? n - 1 : 0);
  if (segments < 2) return result;
  auto a = [&](size_t k) -> const Eigen::Vector2d& { return line.points[k]; };
  auto b = [&](size_t k) -> const Eigen::Vector2d& { return line.points[(k + 1) % n]; };
  for (size_t k = 0; k < segments; ++k) {
    if (!line.closed && k + 1 == segments) break;
    const size_t next = (k + 1) % segments;
    if (DoublesBack(a(k), b(k), b(next))) {
      result = {true, b(k), k, next};
      return result;
    }
  }
  // Sweep in x: sort segments by their left end, test each against those starting before its
  // right end. O(n log n + crossings in x) for the usual drawing.
  std::vector<size_t> order(segments);
  std::iota(order.begin(), order.end(), 0);
  auto min_x = [&](size_t k) { return std::min(a(k).x(), b(k).x()); };
  std::sort(order.begin(), order.end(), [&](size_t p, size_t q) { return min_x(p) < min_x(q); });
  for (size_t i = 0; i < segments; ++i) {
    const size_t s = order[i];
    const double right = std::max(a(s).x(), b(s).x());
    for (size_t j = i + 1; j < segments && min_x(order[j]) <= right; ++j) {
      const size_t t = order[j];
      const size_t lo = std::min(s, t), hi = std::max(s, t);
      const bool adjacent = hi == lo + 1 || (line.closed && lo == 0 && hi == segments - 1);
      if (adjacent) continue;
      Eigen::Vector2d at;
      if (SegmentsMeet(a(s), b(s), a(t), b(t), &at)) {
        result = {true, at, lo, hi};
        return result;
      }
    }
  }
  return result;
}

}  // namespace candi::mesh

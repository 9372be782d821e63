#include "section/section_lines_internal.h"

#include <gtest/gtest.h>

#include <vector>

namespace candi::section::lines_internal {
namespace {

Vertex At(double x, double y) { return {{x, y}, {1, 0}, {0.25, 0.25}}; }

// A bar of 11 vertices 1 m apart along x, and a stem of 2 hanging from its middle (vertex 5).
std::vector<Vertex> TVertices() {
  std::vector<Vertex> v;
  for (int i = 0; i <= 10; ++i) v.push_back(At(i, 0));
  v.push_back(At(5, -1));
  v.push_back(At(5, -2));
  return v;
}

std::vector<Edge> TEdges() {
  std::vector<Edge> edges;
  for (uint32_t i = 0; i < 10; ++i) edges.push_back({i, i + 1, 1.0});
  edges.push_back({5, 11, 1.0});
  edges.push_back({11, 12, 1.0});
  return edges;
}

TEST(LinkVertices, LinksNeighboursAlongTheTangentAndBreaksAtGaps) {
  std::vector<Vertex> v;
  for (int i = 0; i < 5; ++i) v.push_back(At(0.5 * i, 0));
  for (int i = 0; i < 5; ++i) v.push_back(At(12 + 0.5 * i, 0));  // after a 10 m gap
  Context ctx;
  ctx.spacing = 0.5;
  ctx.max_gap = 3;
  ctx.scales.radius = 1.5;
  const std::vector<Edge> edges = LinkVertices(v, ctx);
  ASSERT_EQ(edges.size(), 8u);
  for (const Edge& e : edges) {
    EXPECT_EQ(e.b, e.a + 1);
    EXPECT_NE(e.a, 4u);  // not across the gap
    EXPECT_DOUBLE_EQ(e.length, 0.5);
    EXPECT_TRUE(Linked(edges, e.b, e.a));
  }
  EXPECT_FALSE(Linked(edges, 4, 5));
}

TEST(SpanningForest, DropsTheLongestLinkOfACycleAndMarksItsTree) {
  // A triangle 0-1-2 and a separate pair 3-4.
  const std::vector<Edge> edges = {{0, 1, 1.0}, {0, 2, 1.2}, {1, 2, 1.5}, {3, 4, 1.0}};
  const Forest f = SpanningForest(5, edges);
  EXPECT_EQ(f.degree, (std::vector<uint32_t>{2, 1, 1, 1, 1}));
  EXPECT_EQ(f.loop, (std::vector<uint8_t>{1, 1, 1, 0, 0}));
  EXPECT_EQ(f.alive, (std::vector<uint8_t>(5, 1)));
}

TEST(PruneSpurs, RemovesAShortStemAtAJunctionOnly) {
  const std::vector<Vertex> v = TVertices();
  Forest f = SpanningForest(v.size(), TEdges());
  PruneSpurs(v, 3.0, &f);  // the stem is 2 m, the bar's halves 5 m
  for (uint32_t i = 0; i <= 10; ++i) EXPECT_TRUE(f.alive[i]) << i;
  EXPECT_FALSE(f.alive[11]);
  EXPECT_FALSE(f.alive[12]);
  EXPECT_EQ(f.degree[5], 2u);
  const std::vector<PathLine> paths = SplitPaths(v, f);
  ASSERT_EQ(paths.size(), 1u);
  EXPECT_EQ(paths[0].ids.size(), 11u);
}

TEST(SplitPaths, GivesTheLongestPathThenTheBranchFromItsJunction) {
  const std::vector<Vertex> v = TVertices();
  Forest f = SpanningForest(v.size(), TEdges());
  PruneSpurs(v, 1.5, &f);  // the 2 m stem stays
  const std::vector<PathLine> paths = SplitPaths(v, f);
  ASSERT_EQ(paths.size(), 2u);
  EXPECT_EQ(paths[0].ids, (std::vector<uint32_t>{10, 9, 8, 7, 6, 5, 4, 3, 2, 1, 0}));
  EXPECT_FALSE(paths[0].from_junction);
  EXPECT_EQ(paths[1].ids, (std::vector<uint32_t>{5, 11, 12}));
  EXPECT_TRUE(paths[1].from_junction);
}

}  // namespace
}  // namespace candi::section::lines_internal

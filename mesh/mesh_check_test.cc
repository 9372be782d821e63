#include "mesh/mesh_check.h"

#include <gtest/gtest.h>

namespace candi::mesh {
namespace {

// A unit tetrahedron, faces counter-clockwise seen from outside.
TriMesh Tetrahedron() {
  TriMesh m;
  m.vertices.Resize(4);
  m.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return m;
}

TEST(CheckMesh, ATetrahedronIsAClosedOutwardManifold) {
  const MeshCheckReport r = CheckMesh({}, Tetrahedron());
  EXPECT_TRUE(r.manifold);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.outward);
  EXPECT_FALSE(r.self_intersecting);
  EXPECT_NEAR(r.signed_volume, 1.0 / 6, 1e-15);
  EXPECT_TRUE(r.Ok()) << r.Summary();
}

TEST(CheckMesh, InvertedFacesAreReportedInward) {
  TriMesh m = Tetrahedron();
  for (auto& f : m.faces) std::swap(f[1], f[2]);
  const MeshCheckReport r = CheckMesh({}, m);
  EXPECT_TRUE(r.manifold);
  EXPECT_FALSE(r.outward);
  EXPECT_NE(r.Summary().find("INWARD"), std::string::npos);
}

TEST(CheckMesh, OneFlippedFaceIsNotAnOrientedManifold) {
  TriMesh m = Tetrahedron();
  std::swap(m.faces[3][1], m.faces[3][2]);
  const MeshCheckReport r = CheckMesh({}, m);
  EXPECT_FALSE(r.manifold);
  EXPECT_EQ(r.inconsistent_edges, 3u);
  EXPECT_FALSE(r.Ok());
}

TEST(CheckMesh, ThreeFacesOnAnEdgeAreNonManifold) {
  TriMesh m;
  m.vertices.Resize(5);
  m.vertices.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
  m.faces = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
  const MeshCheckReport r = CheckMesh({}, m);
  EXPECT_FALSE(r.manifold);
  EXPECT_EQ(r.non_manifold_edges, 1u);
}

TEST(CheckMesh, CrossingSheetsSelfIntersect) {
  TriMesh m;
  m.vertices.Resize(6);
  m.vertices.positions = {{0, 0, 0},      {2, 0, 0},     {0, 2, 0},
                          {0.5, 0.5, -1}, {0.5, 0.5, 1}, {3, 3, 0.5}};
  m.faces = {{0, 1, 2}, {3, 5, 4}};
  MeshCheckReport r = CheckMesh({}, m);
  EXPECT_TRUE(r.manifold);
  EXPECT_TRUE(r.self_intersecting);
  EXPECT_NE(r.Summary().find("SELF-INTERSECTING"), std::string::npos);
  MeshCheckOptions o;
  o.self_intersections = false;
  r = CheckMesh(o, m);
  EXPECT_FALSE(r.self_intersections_checked);
}

}  // namespace
}  // namespace candi::mesh

#include "mesh/surface_mesh.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>

#include "mesh/mesh_check.h"
#include "mesh/open_mesh.h"

namespace candi::mesh {
namespace {

using V = Eigen::Vector2d;
const SectionSource kAnalyticSource{"analytic", "shape"};

SurfaceGrid Revolve(const std::vector<V>& section, int n, int m, bool closed = false) {
  ProfileOptions po;
  po.samples_per_side = n;
  RevolveOptions ro;
  ro.angular_steps = m;
  return RevolveProfile(ro, BuildProfile(po, {section, closed}, kAnalyticSource));
}

// A cone of radius R and height H, apex up: the section (-R, 0) (0, H) (R, 0).
constexpr double kR = 10, kH = 6;
std::vector<V> Cone() { return {V(-kR, 0), V(0, kH), V(kR, 0)}; }

// The upper half of a circle of radius kR about (0, 0), from 4001 exact vertices.
std::vector<V> Hemisphere() {
  std::vector<V> pts;
  for (int k = 0; k <= 4000; ++k) {
    const double a = M_PI * (1 - k / 4000.0);
    pts.emplace_back(kR * std::cos(a), kR * std::sin(a));
  }
  return pts;
}

// Largest distance from the analytic surface over triangle centroids (world = local + shift).
double CentroidError(const TriMesh& mesh, const std::function<double(const Eigen::Vector3d&)>& d) {
  double worst = 0;
  const auto& p = mesh.vertices.positions;
  for (const auto& f : mesh.faces) {
    const Eigen::Vector3d c = (p[f[0]] + p[f[1]] + p[f[2]]) / 3 + mesh.vertices.frame.origin;
    worst = std::max(worst, std::abs(d(c)));
  }
  return worst;
}

double ConeDistance(const Eigen::Vector3d& q) {
  const double rho = std::hypot(q.x(), q.y());
  return (rho * kH + q.z() * kR - kR * kH) / std::hypot(kR, kH);
}
double SphereDistance(const Eigen::Vector3d& q) { return q.norm() - kR; }

// log2(e(h) / e(h/2)) for successive doublings.
std::vector<double> Orders(const std::vector<double>& errors) {
  std::vector<double> orders;
  for (size_t k = 0; k + 1 < errors.size(); ++k)
    orders.push_back(std::log2(errors[k] / errors[k + 1]));
  return orders;
}

TEST(BuildSurfaceMesh, CountsApexAndCheckedOrientation) {
  const SurfaceGrid g = Revolve(Cone(), 11, 6);
  ASSERT_TRUE(g.apex_top);
  const TriMesh mesh = BuildSurfaceMesh({}, g);
  EXPECT_EQ(mesh.vertices.size(), 1u + 10 * 12);
  EXPECT_EQ(mesh.faces.size(), 12u + 2 * 9 * 12);
  const MeshCheckReport r = CheckMesh({}, mesh);
  EXPECT_TRUE(r.manifold);
  EXPECT_FALSE(r.closed);
  EXPECT_EQ(r.boundary_edges, 12u);
  EXPECT_FALSE(r.self_intersecting);
  EXPECT_TRUE(r.outward) << r.Summary();
  EXPECT_TRUE(r.Ok()) << r.Summary();
}

TEST(BuildSurfaceMesh, ClosingTheBaseMakesAnOutwardSolidOfTheConesVolume) {
  SurfaceMeshOptions o;
  o.close_base = true;
  const TriMesh mesh = BuildSurfaceMesh(o, Revolve(Cone(), 5, 128));
  const MeshCheckReport r = CheckMesh({}, mesh);
  EXPECT_TRUE(r.closed) << r.Summary();
  EXPECT_TRUE(r.Ok()) << r.Summary();
  const double exact = M_PI * kR * kR * kH / 3;
  // The inscribed 256-gon's area is sin(2 pi / 256) / (2 pi / 256) of the circle's.
  EXPECT_NEAR(r.signed_volume, exact * std::sin(2 * M_PI / 256) / (2 * M_PI / 256), 1e-9 * exact);
}

TEST(BuildSurfaceMesh, AClosedSectionGivesAClosedSolidWithTwoApexes) {
  const SurfaceGrid g = Revolve({V(0, -2), V(1, 0), V(0, 2), V(-1, 0)}, 20, 16, true);
  EXPECT_TRUE(g.apex_top);
  EXPECT_TRUE(g.apex_bottom);
  const MeshCheckReport r = CheckMesh({}, BuildSurfaceMesh({}, g));
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.Ok()) << r.Summary();
}

// The directly indexed triangles are a valid OpenMesh halfedge mesh: OpenMesh accepts every face
// (no non-manifold or flipped one; ToOpenMesh would throw), returns the same mesh, and its
// boundary is the expected rings. Covers an apex, a closed base on a blended (asymmetric) grid,
// and two apexes.
TEST(BuildSurfaceMesh, OpenMeshAcceptsEveryFaceAndGivesTheSameMeshBack) {
  SurfaceMeshOptions closed;
  closed.close_base = true;
  const std::vector<V> lopsided = {V(-7, -1), V(-3, 2), V(0, 5), V(4, 1), V(9, -2)};
  const struct {
    SurfaceGrid grid;
    SurfaceMeshOptions options;
    size_t boundary;  // boundary halfedges
  } cases[] = {{Revolve(Cone(), 11, 6), {}, 12},
               {Revolve(lopsided, 9, 5), closed, 0},
               {Revolve(lopsided, 9, 5), {}, 10},
               {Revolve({V(0, -2), V(1, 0), V(0, 2), V(-1, 0)}, 20, 16, true), {}, 0}};
  for (const auto& c : cases) {
    const TriMesh mesh = BuildSurfaceMesh(c.options, c.grid);
    const internal::OpenTriMesh om = internal::ToOpenMesh(mesh);
    EXPECT_EQ(om.n_faces(), mesh.faces.size());
    size_t boundary = 0;
    for (const auto h : om.halfedges()) boundary += om.is_boundary(h);
    EXPECT_EQ(boundary, c.boundary);
    const TriMesh back = internal::FromOpenMesh(om, mesh.vertices.frame);
    EXPECT_EQ(back.vertices.positions, mesh.vertices.positions);
    EXPECT_EQ(back.faces, mesh.faces);
    EXPECT_TRUE(CheckMesh({}, mesh).Ok()) << CheckMesh({}, mesh).Summary();
  }
}

TEST(SweepConvergence, ConeApproachesTheTheAnalyticSurfaceAtSecondOrderInAngularSteps) {
  std::vector<double> errors;
  for (int m : {8, 16, 32, 64, 128}) {
    errors.push_back(CentroidError(BuildSurfaceMesh({}, Revolve(Cone(), 20, m)), ConeDistance));
  }
  for (double order : Orders(errors))
    EXPECT_NEAR(order, 2.0, 0.15) << ::testing::PrintToString(errors);
}

TEST(SweepConvergence, HemisphereApproachesTheSphereAtSecondOrder) {
  // N and M doubled together: the centroid error (chordal, both directions) falls as h^2.
  std::vector<double> errors;
  for (int k : {8, 16, 32, 64, 128}) {
    errors.push_back(
        CentroidError(BuildSurfaceMesh({}, Revolve(Hemisphere(), k + 1, 2 * k)), SphereDistance));
  }
  for (double order : Orders(errors))
    EXPECT_NEAR(order, 2.0, 0.2) << ::testing::PrintToString(errors);
  // N alone (M large): the profile's chords, error h^2 / 8R with h the arc per step.
  std::vector<double> along;
  for (int n : {9, 17, 33, 65}) {
    const SurfaceGrid g = Revolve(Hemisphere(), n, 4);
    double worst = 0;
    for (int i = 0; i + 1 < g.rings; ++i) {
      const Eigen::Vector3d mid = (g.At(i, 0) + g.At(i + 1, 0)) / 2 + g.frame.origin;
      worst = std::max(worst, std::abs(SphereDistance(mid)));
    }
    along.push_back(worst);
    const double h = M_PI * kR / 2 / (n - 1);
    EXPECT_NEAR(worst, h * h / (8 * kR), 0.02 * h * h / (8 * kR)) << n;
  }
  for (double order : Orders(along)) EXPECT_NEAR(order, 2.0, 0.1);
}

}  // namespace
}  // namespace candi::mesh

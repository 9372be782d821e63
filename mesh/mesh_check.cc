#include "mesh/mesh_check.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/measure.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/orientation.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Polygon_mesh_processing/shape_predicates.h>
#include <CGAL/Surface_mesh.h>

#include <Eigen/Geometry>
#include <array>
#include <unordered_map>
#include <vector>

#include "core/check.h"

namespace candi::mesh {

namespace {

namespace PMP = CGAL::Polygon_mesh_processing;
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point3 = Kernel::Point_3;
using CgalMesh = CGAL::Surface_mesh<Point3>;

uint64_t EdgeKey(uint32_t a, uint32_t b) { return (uint64_t{a} << 32) | b; }

// Counts edge uses directly (CGAL's soup test says only yes or no).
void CountEdges(const TriMesh& mesh, MeshCheckReport* report) {
  std::unordered_map<uint64_t, std::array<uint32_t, 2>> uses;  // undirected -> (a->b, b->a)
  uses.reserve(mesh.faces.size() * 2);
  for (const auto& f : mesh.faces) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = f[k], b = f[(k + 1) % 3];
      auto& count = uses[EdgeKey(std::min(a, b), std::max(a, b))];
      ++count[a < b ? 0 : 1];
    }
  }
  for (const auto& [key, count] : uses) {
    const uint32_t total = count[0] + count[1];
    if (total == 1) ++report->boundary_edges;
    if (total > 2) ++report->non_manifold_edges;
    if (count[0] > 1 || count[1] > 1) ++report->inconsistent_edges;
  }
}

// Signed volume of the surface closed by a fan to the boundary's centroid (see the header).
double SignedVolume(const TriMesh& mesh, const Eigen::Vector3d& centre) {
  double volume = 0;
  const auto& p = mesh.vertices.positions;
  for (const auto& f : mesh.faces) {
    volume += (p[f[0]] - centre).dot((p[f[1]] - centre).cross(p[f[2]] - centre)) / 6;
  }
  return volume;
}

Eigen::Vector3d BoundaryCentroid(const CgalMesh& cm, const TriMesh& mesh) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  size_t count = 0;
  for (const auto h : cm.halfedges()) {
    if (!cm.is_border(h)) continue;
    sum += mesh.vertices.positions[static_cast<size_t>(cm.target(h))];
    ++count;
  }
  return count ? Eigen::Vector3d(sum / static_cast<double>(count)) : Eigen::Vector3d::Zero();
}

}  // namespace

bool MeshCheckReport::Ok() const {
  return manifold && degenerate_faces == 0 && !self_intersecting && outward;
}

std::string MeshCheckReport::Summary() const {
  std::string s = manifold ? "manifold" : "NOT manifold";
  if (non_manifold_edges) s += " (" + std::to_string(non_manifold_edges) + " non-manifold edges)";
  if (inconsistent_edges) s += " (" + std::to_string(inconsistent_edges) + " flipped edges)";
  s += closed ? ", closed" : ", open (" + std::to_string(boundary_edges) + " boundary edges)";
  if (degenerate_faces) s += ", " + std::to_string(degenerate_faces) + " degenerate faces";
  if (self_intersections_checked) {
    s += self_intersecting ? ", SELF-INTERSECTING" : ", no self-intersections";
  } else {
    s += ", self-intersections not checked";
  }
  s += outward ? ", outward oriented" : ", INWARD oriented";
  return s;
}

MeshCheckReport CheckMesh(const MeshCheckOptions& options, const TriMesh& mesh) {
  options.Check();
  MeshCheckReport report;
  report.vertices = mesh.vertices.size();
  report.faces = mesh.faces.size();
  CountEdges(mesh, &report);
  report.closed = report.boundary_edges == 0;
  std::vector<Point3> points;
  points.reserve(mesh.vertices.size());
  for (const Eigen::Vector3d& p : mesh.vertices.positions) points.emplace_back(p.x(), p.y(), p.z());
  std::vector<std::array<size_t, 3>> polygons;
  polygons.reserve(mesh.faces.size());
  for (const auto& f : mesh.faces) polygons.push_back({f[0], f[1], f[2]});
  report.manifold = PMP::is_polygon_soup_a_polygon_mesh(polygons);
  if (!report.manifold) return report;  // CGAL's mesh tests need a polygon mesh
  CgalMesh cm;
  PMP::polygon_soup_to_polygon_mesh(points, polygons, cm);
  CANDI_CHECK_EQ(cm.number_of_vertices(), mesh.vertices.size());
  for (const auto f : cm.faces())
    report.degenerate_faces += PMP::is_degenerate_triangle_face(f, cm);
  report.area = PMP::area(cm);
  if (options.self_intersections) {
    report.self_intersections_checked = true;
    report.self_intersecting = PMP::does_self_intersect(cm);
  }
  const Eigen::Vector3d centre =
      report.closed ? mesh.vertices.positions.front() : BoundaryCentroid(cm, mesh);
  report.signed_volume = SignedVolume(mesh, centre);
  report.outward = report.closed && report.degenerate_faces == 0 ? PMP::is_outward_oriented(cm)
                                                                 : report.signed_volume > 0;
  return report;
}

}  // namespace candi::mesh

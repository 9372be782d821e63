// C2M: the distance from each compared point to a triangle mesh, by CGAL's AABB tree, signed by
// angle-weighted pseudo-normals (Baerentzen & Aanaes 2005, "Signed distance computation using
// the angle weighted pseudonormal").
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "compare/deviation_internal.h"
#include "core/check.h"
#include "core/parallel.h"

namespace candi::compare {

namespace {

using Kernel = CGAL::Simple_cartesian<double>;
using Triangle = Kernel::Triangle_3;
using TriangleIterator = std::vector<Triangle>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Kernel::Point_3 ToCgal(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }
Eigen::Vector3d ToEigen(const Kernel::Point_3& p) { return {p.x(), p.y(), p.z()}; }

uint64_t EdgeKey(uint32_t a, uint32_t b) {
  return a < b ? (uint64_t{a} << 32) | b : (uint64_t{b} << 32) | a;
}

// The mesh's usable triangles with the pseudo-normals of their faces, edges and vertices.
struct SignedMesh {
  std::vector<std::array<uint32_t, 3>> faces;  // non-degenerate faces only
  std::vector<Triangle> triangles;             // the same, as CGAL triangles
  std::vector<Eigen::Vector3d> face_normals;   // unit
  std::vector<Eigen::Vector3d> vertex_normals;  // angle-weighted sums (not normalised)
  std::unordered_map<uint64_t, Eigen::Vector3d> edge_normals;  // sums of the faces' normals
};

SignedMesh BuildSignedMesh(const std::vector<Eigen::Vector3d>& v,
                           const std::vector<std::array<uint32_t, 3>>& faces,
                           const std::string& name, uint64_t& degenerate) {
  SignedMesh m;
  m.vertex_normals.assign(v.size(), Eigen::Vector3d::Zero());
  degenerate = 0;
  for (size_t f = 0; f < faces.size(); ++f) {
    const auto& t = faces[f];
    for (int k = 0; k < 3; ++k) {
      if (t[k] >= v.size()) {
        throw InputError(name, "face " + std::to_string(f),
                         "vertex index " + std::to_string(t[k]) + " out of range (" +
                             std::to_string(v.size()) + " vertices)");
      }
      if (!v[t[k]].allFinite()) {
        throw InputError(name, "vertex " + std::to_string(t[k]), "position is not finite");
      }
    }
    const Eigen::Vector3d cross = (v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]);
    const double area2 = cross.norm();
    const double scale = std::max({(v[t[1]] - v[t[0]]).squaredNorm(),
                                   (v[t[2]] - v[t[0]]).squaredNorm(),
                                   (v[t[2]] - v[t[1]]).squaredNorm()});
    if (!(area2 > 1e-12 * scale)) {
      ++degenerate;
      continue;
    }
    const Eigen::Vector3d normal = cross / area2;
    m.faces.push_back(t);
    m.face_normals.push_back(normal);
    m.triangles.emplace_back(ToCgal(v[t[0]]), ToCgal(v[t[1]]), ToCgal(v[t[2]]));
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d a = (v[t[(k + 1) % 3]] - v[t[k]]).normalized();
      const Eigen::Vector3d b = (v[t[(k + 2) % 3]] - v[t[k]]).normalized();
      const double angle = std::acos(std::clamp(a.dot(b), -1.0, 1.0));
      m.vertex_normals[t[k]] += angle * normal;
      // emplace: a new entry starts at zero (Eigen's default constructor leaves it unset).
      m.edge_normals.emplace(EdgeKey(t[k], t[(k + 1) % 3]), Eigen::Vector3d::Zero())
          .first->second += normal;
    }
  }
  if (m.faces.empty()) {
    throw InputError(name, "", faces.empty()
                                   ? "the mesh has no faces: C2M needs triangles"
                                   : "every face of the mesh is degenerate (zero area)");
  }
  return m;
}

// The pseudo-normal at the point c of face f nearest q: the face's, an edge's or a vertex's,
// by which of c's barycentric coordinates vanish.
Eigen::Vector3d PseudoNormal(const SignedMesh& m, const std::vector<Eigen::Vector3d>& v, size_t f,
                             const Eigen::Vector3d& c) {
  const auto& t = m.faces[f];
  const Eigen::Vector3d a = v[t[0]], e1 = v[t[1]] - a, e2 = v[t[2]] - a, d = c - a;
  const double d00 = e1.dot(e1), d01 = e1.dot(e2), d11 = e2.dot(e2);
  const double d20 = d.dot(e1), d21 = d.dot(e2);
  const double den = d00 * d11 - d01 * d01;
  const double b1 = (d11 * d20 - d01 * d21) / den, b2 = (d00 * d21 - d01 * d20) / den;
  const double bary[3] = {1 - b1 - b2, b1, b2};
  constexpr double kEps = 1e-9;
  int zero = 0, nonzero[3], count_nonzero = 0;
  for (int k = 0; k < 3; ++k) {
    if (bary[k] <= kEps) {
      ++zero;
    } else {
      nonzero[count_nonzero++] = k;
    }
  }
  if (zero == 1) return m.edge_normals.at(EdgeKey(t[nonzero[0]], t[nonzero[1]]));
  if (zero == 2) return m.vertex_normals[t[nonzero[0]]];
  return m.face_normals[f];
}

}  // namespace

DeviationResult CompareToMesh(const DeviationOptions& options, const TriMesh& reference,
                              const PointCloud& compared, const std::string& reference_name,
                              const std::string& compared_name,
                              const ProgressCallback& progress) {
  options.Check();
  internal::CheckNotEmpty(reference.faces.size(), reference_name, "faces");
  internal::CheckNotEmpty(compared.size(), compared_name);
  internal::CheckBelowIndexLimit(compared.size(), compared_name);
  const Eigen::Vector3d origin = internal::CommonOrigin(internal::FiniteWorldBounds(reference.vertices));
  const std::vector<Eigen::Vector3d> v = internal::RelativePositions(reference.vertices, origin);
  uint64_t degenerate = 0;
  const SignedMesh mesh = BuildSignedMesh(v, reference.faces, reference_name, degenerate);
  Tree tree(mesh.triangles.begin(), mesh.triangles.end());
  tree.build();  // now, not lazily under the workers' first queries
  tree.accelerate_distance_queries();

  const std::vector<Eigen::Vector3d> q = internal::RelativePositions(compared, origin);
  uint64_t not_finite = 0;
  for (const auto& p : q) not_finite += p.allFinite() ? 0 : 1;
  DeviationResult result;
  result.method = Method::kC2M;
  result.distance.assign(q.size(), std::numeric_limits<double>::quiet_NaN());
  const std::vector<uint32_t> order = internal::MortonOrder(q);
  ForEachBlock(options.threads, q.size(), internal::kBlock, progress, [&](size_t begin, size_t end) {
    for (size_t j = begin; j < end; ++j) {
      const size_t i = order[j];
      if (!q[i].allFinite()) continue;
      const auto hit = tree.closest_point_and_primitive(ToCgal(q[i]));
      const Eigen::Vector3d c = ToEigen(hit.first);
      const size_t f = static_cast<size_t>(hit.second - mesh.triangles.begin());
      const Eigen::Vector3d offset = q[i] - c;
      double d = offset.norm();
      if (options.c2m.signed_distance && d > 0 &&
          offset.dot(PseudoNormal(mesh, v, f, c)) < 0) {
        d = -d;
      }
      result.distance[i] = d;
    }
  });
  if (degenerate > 0) {
    result.warnings.push_back(reference_name + ": " + std::to_string(degenerate) +
                              " degenerate face(s) (zero area) were left out");
  }
  internal::Finish(result, not_finite,
                   internal::BoxGap(internal::FiniteWorldBounds(reference.vertices),
                                    internal::FiniteWorldBounds(compared)),
                   compared_name);
  return result;
}

}  // namespace candi::compare

#include "mesh/surface_mesh.h"

#include "core/check.h"
#include "mesh/open_mesh.h"

namespace candi {

namespace {

using internal::OpenTriMesh;
using VertexHandle = OpenTriMesh::VertexHandle;

void AddFace(OpenTriMesh* om, VertexHandle a, VertexHandle b, VertexHandle c) {
  const auto face = om->add_face(a, b, c);
  CANDI_CHECK(face.is_valid()) << "BuildSurfaceMesh: face " << a.idx() << " " << b.idx() << " "
                               << c.idx() << " rejected";
}

// Closes the bottom ring with a fan around a vertex on the axis: each new face runs along the
// ring's free (boundary) halfedge, so its orientation follows the surface's.
void CloseBase(const SurfaceGrid& grid, const std::vector<VertexHandle>& bottom, OpenTriMesh* om) {
  Eigen::Vector3d centre = grid.axis_point;
  double height = 0;
  for (int j = 0; j < grid.columns; ++j) height += grid.At(grid.rings - 1, j).z();
  centre.z() = height / grid.columns;
  const VertexHandle c = om->add_vertex(OpenMesh::Vec3d(centre.x(), centre.y(), centre.z()));
  for (size_t j = 0; j < bottom.size(); ++j) {
    const VertexHandle a = bottom[j], b = bottom[(j + 1) % bottom.size()];
    const auto h = om->find_halfedge(a, b);
    if (h.is_valid() && om->is_boundary(h)) {
      AddFace(om, a, b, c);
    } else {
      AddFace(om, b, a, c);
    }
  }
}

}  // namespace

TriMesh BuildSurfaceMesh(const SurfaceMeshOptions& options, const SurfaceGrid& grid) {
  const int n = grid.rings, cols = grid.columns;
  CANDI_CHECK(n >= 2 && cols >= 3 &&
              grid.positions.size() == static_cast<size_t>(n) * static_cast<size_t>(cols))
      << "BuildSurfaceMesh: " << n << " rings, " << cols << " columns, " << grid.positions.size()
      << " positions";
  OpenTriMesh om;
  const size_t faces = 2 * static_cast<size_t>(n) * static_cast<size_t>(cols);
  om.reserve(static_cast<size_t>(n) * cols + 1, 3 * faces / 2 + cols, faces + cols);
  std::vector<std::vector<VertexHandle>> rings(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) {
    const bool apex = (i == 0 && grid.apex_top) || (i == n - 1 && grid.apex_bottom);
    for (int j = 0; j < (apex ? 1 : cols); ++j) {
      const Eigen::Vector3d& p = grid.At(i, j);
      rings[i].push_back(om.add_vertex(OpenMesh::Vec3d(p.x(), p.y(), p.z())));
    }
  }
  auto vertex = [&](int i, int j) { return rings[i].size() == 1 ? rings[i][0] : rings[i][j]; };
  for (int i = 0; i + 1 < n; ++i) {
    for (int j = 0; j < cols; ++j) {
      const int next = (j + 1) % cols;
      const VertexHandle a = vertex(i, j), b = vertex(i, next);
      const VertexHandle c = vertex(i + 1, j), d = vertex(i + 1, next);
      if (a != b) AddFace(&om, a, b, c);
      if (c != d) AddFace(&om, c, b, d);
    }
  }
  if (options.close_base && !grid.apex_bottom) CloseBase(grid, rings[n - 1], &om);
  return internal::FromOpenMesh(om, grid.frame);
}

}  // namespace candi

#include "mesh/surface_mesh.h"

#include "core/check.h"

namespace candi::mesh {

TriMesh BuildSurfaceMesh(const SurfaceMeshOptions& options, const SurfaceGrid& grid) {
  options.Check();
  const int n = grid.rings, cols = grid.columns;
  CANDI_CHECK(n >= 2 && cols >= 3 &&
              grid.positions.size() == static_cast<size_t>(n) * static_cast<size_t>(cols))
      << "BuildSurfaceMesh: " << n << " rings, " << cols << " columns, " << grid.positions.size()
      << " positions";
  const bool close = options.close_base && !grid.apex_bottom;
  // Ring i's first vertex index; an apex ring is one vertex (the grid's column 0).
  std::vector<uint32_t> first(static_cast<size_t>(n) + 1, 0);
  auto ring_size = [&](int i) {
    const bool apex = (i == 0 && grid.apex_top) || (i == n - 1 && grid.apex_bottom);
    return apex ? 1u : static_cast<uint32_t>(cols);
  };
  for (int i = 0; i < n; ++i) first[i + 1] = first[i] + ring_size(i);
  TriMesh mesh;
  mesh.vertices.frame = grid.frame;
  mesh.vertices.Resize(first[n] + (close ? 1 : 0));
  auto& positions = mesh.vertices.positions;
  for (int i = 0; i < n; ++i) {
    for (uint32_t j = 0; j < ring_size(i); ++j) positions[first[i] + j] = grid.At(i, static_cast<int>(j));
  }
  auto vertex = [&](int i, int j) {
    return first[i + 1] - first[i] == 1 ? first[i] : first[i] + static_cast<uint32_t>(j);
  };
  mesh.faces.reserve(2 * static_cast<size_t>(n - 1) * static_cast<size_t>(cols) + (close ? cols : 0));
  for (int i = 0; i + 1 < n; ++i) {
    for (int j = 0; j < cols; ++j) {
      const int next = (j + 1) % cols;
      const uint32_t a = vertex(i, j), b = vertex(i, next);
      const uint32_t c = vertex(i + 1, j), d = vertex(i + 1, next);
      if (a != b) mesh.faces.push_back({a, b, c});
      if (c != d) mesh.faces.push_back({c, b, d});
    }
  }
  if (close) {
    // A fan around a vertex on the axis at the bottom ring's mean height. The last strip's faces
    // (c, b, d) run along the bottom ring from column j + 1 to j, so the ring's free side runs
    // from j to j + 1 and each fan face (j, j + 1, centre) continues the surface's orientation.
    Eigen::Vector3d centre = grid.axis_point;
    double height = 0;
    for (int j = 0; j < cols; ++j) height += grid.At(n - 1, j).z();
    centre.z() = height / cols;
    const uint32_t c = first[n];
    positions[c] = centre;
    for (int j = 0; j < cols; ++j) {
      mesh.faces.push_back({first[n - 1] + static_cast<uint32_t>(j),
                            first[n - 1] + static_cast<uint32_t>((j + 1) % cols), c});
    }
  }
  return mesh;
}

}  // namespace candi::mesh

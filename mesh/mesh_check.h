// Checks of a triangle mesh with CGAL: 2-manifoldness, self-intersections, orientation.
//
// The edge counts (edges of more than two faces, edges two faces run the same way, boundary
// edges) are counted directly; CGAL decides whether the triangles form a polygon mesh
// (is_polygon_soup_a_polygon_mesh: manifold edges and vertices, consistent orientation), whether
// faces intersect (does_self_intersect, exact predicates) and, for a closed mesh, whether it is
// outward oriented (is_outward_oriented). For an open surface "outward" means a positive signed
// volume of the surface closed by a fan to its boundary's centroid (a dome whose normals point up
// and away from its axis is outward). Problems are results in the report, never exceptions.
// Cost: self-intersection O(F log F) (box intersection); switch it off for very large meshes.
// Thread-safe (pure function).
#pragma once

#include <cstddef>
#include <string>

#include "core/tri_mesh.h"

namespace candi::mesh {

struct MeshCheckOptions {
  bool self_intersections = true;  // run CGAL's self-intersection test
  void Check() const {}            // every value is valid (a flag)
};

struct MeshCheckReport {
  size_t vertices = 0, faces = 0;
  bool manifold = false;          // CGAL: the faces form an oriented 2-manifold polygon mesh
  size_t non_manifold_edges = 0;  // edges of more than two faces
  size_t inconsistent_edges = 0;  // edges two faces traverse in the same direction
  size_t boundary_edges = 0;      // edges of one face
  size_t degenerate_faces = 0;    // faces of zero area (CGAL: collinear corners)
  bool closed = false;            // no boundary edges
  bool self_intersections_checked = false;
  bool self_intersecting = false;
  bool outward = false;      // see the file comment
  double area = 0;           // m^2
  double signed_volume = 0;  // m^3 (closed: the volume; open: closed by the boundary centroid)

  bool Ok() const;
  std::string Summary() const;  // one line: "manifold, open (180 boundary edges), ..."
};

MeshCheckReport CheckMesh(const MeshCheckOptions& options, const TriMesh& mesh);

}  // namespace candi::mesh

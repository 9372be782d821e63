// The triangle mesh of a revolved surface (ALGORITHMS.md §2, step 4).
//
// The grid's topology is fixed, so the triangles are written directly by index (milliseconds for
// the paper's 360 k triangles per layer; building them face by face in OpenMesh took ~0.1 s per
// layer). internal::ToOpenMesh (mesh/open_mesh.h) gives the OpenMesh halfedge mesh where one is
// needed; surface_mesh_test checks that OpenMesh accepts every face and returns the same mesh.
// Grid cell (ring i, column j)-(i+1, j+1) is a quad split into triangles (i,j)(i,j+1)(i+1,j) and
// (i+1,j)(i,j+1)(i+1,j+1), columns wrapping around; a ring on the axis (apex) is one vertex and
// its cells are single triangles. Faces are counter-clockwise seen from outside (normals point
// away from the axis and up for a hill drawn from its top outward). close_base closes the
// bottom ring (when it is not an apex) with a fan around a new vertex on the axis at the ring's
// mean height, oriented consistently (normals down). The mesh keeps the grid's local frame.
// Thread-safe (pure function); bad grids (fewer than 2 rings or 3 columns) are CANDI_CHECK.
#pragma once

#include "core/tri_mesh.h"
#include "mesh/revolve.h"

namespace candi::mesh {

struct SurfaceMeshOptions {
  bool close_base = false;  // close the bottom ring with a fan (a watertight solid for a dome)
  void Check() const {}     // every value is valid (a flag)
};

TriMesh BuildSurfaceMesh(const SurfaceMeshOptions& options, const SurfaceGrid& grid);

}  // namespace candi::mesh

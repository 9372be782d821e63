// Private to mesh/*.cc (never included by a public header: OpenMesh is heavy): the OpenMesh type
// candi builds surfaces in, and the conversion to core's TriMesh.
#pragma once

// OpenMesh's VectorT default constructor leaves its elements uninitialised by design, and
// GCC 12 warns where PropertyT::push_back copies one (inlined into this TU): not a candi bug.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

#include "core/check.h"
#include "core/tri_mesh.h"

namespace candi::mesh::internal {

struct OpenMeshTraits : public OpenMesh::DefaultTraits {
  typedef OpenMesh::Vec3d Point;  // double: local coordinates keep millimetres at any scale
  typedef OpenMesh::Vec3d Normal;
};
using OpenTriMesh = OpenMesh::TriMesh_ArrayKernelT<OpenMeshTraits>;

// The halfedge mesh of a triangle mesh: vertices and faces in index order. A face OpenMesh
// rejects (a non-manifold edge or vertex, a flipped neighbour) is InternalError naming it.
inline OpenTriMesh ToOpenMesh(const TriMesh& mesh) {
  OpenTriMesh om;
  om.reserve(mesh.vertices.size(), mesh.faces.size() * 3 / 2 + mesh.vertices.size(), mesh.faces.size());
  std::vector<OpenTriMesh::VertexHandle> handles;
  handles.reserve(mesh.vertices.size());
  for (const Eigen::Vector3d& p : mesh.vertices.positions) {
    handles.push_back(om.add_vertex(OpenMesh::Vec3d(p.x(), p.y(), p.z())));
  }
  for (const auto& f : mesh.faces) {
    const auto face = om.add_face(handles.at(f[0]), handles.at(f[1]), handles.at(f[2]));
    CANDI_CHECK(face.is_valid()) << "ToOpenMesh: face " << f[0] << " " << f[1] << " " << f[2]
                                 << " rejected";
  }
  return om;
}

// Vertices in index order, faces in index order; colours, normals and fields are not copied.
inline TriMesh FromOpenMesh(const OpenTriMesh& om, const LocalFrame& frame) {
  TriMesh mesh;
  mesh.vertices.frame = frame;
  mesh.vertices.Resize(om.n_vertices());
  for (const auto v : om.vertices()) {
    const OpenMesh::Vec3d& p = om.point(v);
    mesh.vertices.positions[static_cast<size_t>(v.idx())] = Eigen::Vector3d(p[0], p[1], p[2]);
  }
  mesh.faces.reserve(om.n_faces());
  for (const auto f : om.faces()) {
    std::array<uint32_t, 3> tri{};
    int k = 0;
    for (const auto v : om.fv_range(f)) tri[k++] = static_cast<uint32_t>(v.idx());
    mesh.faces.push_back(tri);
  }
  return mesh;
}

}  // namespace candi::mesh::internal

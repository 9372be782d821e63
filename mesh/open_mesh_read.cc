#include "mesh/open_mesh_read.h"

// OpenMesh's IO must be included before any mesh kernel header (the warning: see open_mesh.h).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <OpenMesh/Core/IO/MeshIO.hh>

#include "core/check.h"
#include "io/shift_sidecar.h"
#include "mesh/open_mesh.h"

namespace candi::mesh {

TriMesh ReadMesh(const std::string& path) {
  internal::OpenTriMesh om;
  if (!OpenMesh::IO::read_mesh(om, path)) {
    throw InputError(path, "", "OpenMesh could not read the mesh");
  }
  const std::optional<LocalFrame> shift = io::ReadShiftSidecar(path);
  return internal::FromOpenMesh(om, shift ? *shift : LocalFrame());
}

}  // namespace candi::mesh

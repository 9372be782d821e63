// An independent reader of triangle meshes through OpenMesh (OBJ, OFF, PLY; it parses float), for
// tests and tools. candi reads and writes its mesh files with io/mesh_io.h.
#pragma once

#include <string>

#include "core/tri_mesh.h"

namespace candi::mesh {

// Reads an OBJ, OFF or PLY mesh with OpenMesh; positions local, the shift sidecar's frame applied
// when present. InputError when it cannot be read.
TriMesh ReadMesh(const std::string& path);

}  // namespace candi::mesh

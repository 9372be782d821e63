// Writing a triangle mesh as OBJ or OFF (text, shortest round-trip digits: OpenMesh's writers go
// through float) or PLY (core's binary PLY writer, double positions), chosen by the extension;
// files MeshLab and OpenMesh open.
// Positions are written in the mesh's local frame; a non-zero shift is kept beside the file
// ("<path>.shift.json"; PLY also as "comment candi_shift"), as the point writers do.
// Writes are atomic (temporary file, then rename). Failures: InputError naming the path (unknown
// extension, unwritable folder). Thread-safe for distinct paths.
#pragma once

#include <string>

#include "core/tri_mesh.h"

namespace candi::mesh {

void WriteMesh(const std::string& path, const TriMesh& mesh);

// Reads an OBJ, OFF or PLY mesh with OpenMesh (an independent reader, for tests and tools; it
// parses float); positions local, the shift sidecar's frame applied when present. InputError
// when it cannot be read.
TriMesh ReadMesh(const std::string& path);

}  // namespace candi::mesh

// Triangle meshes read and written by their extension: the one dispatcher of mesh files, the
// formats' own code in io/ply/ (PLY) and io/obj/ (the OBJ reader).
//
// WriteMesh: .ply (io/ply: binary PLY, double positions), .obj or .off (text, shortest round-trip
// digits: OpenMesh's writers go through float), files MeshLab and OpenMesh open. Positions are
// written in the mesh's local frame; a non-zero shift is kept beside the file
// ("<path>.shift.json"; PLY also as "comment candi_shift"), as the point writers do. Writes are
// atomic (temporary file, then rename). Failures: InputError naming the path (unknown extension,
// unwritable folder).
// ReadMesh: .ply (io/ply) or .obj (io/obj), in double precision, the shift sidecar applied.
// Failures: InputError naming the path (another extension, a file that cannot be read).
// Thread-safe for distinct paths.
#pragma once

#include <string>

#include "core/tri_mesh.h"

namespace candi::io {

void WriteMesh(const std::string& path, const TriMesh& mesh);

TriMesh ReadMesh(const std::string& path);

}  // namespace candi::io

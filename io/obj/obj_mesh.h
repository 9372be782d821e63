// Wavefront OBJ meshes, read in double precision (OpenMesh's reader, mesh/open_mesh_read.h, parses
// float, which keeps only ~0.1 m at survey coordinates): `v x y z [w]` (a vertex colour after it,
// r g b in 0-1, is kept), `f a b c ...` with `a`, `a/t`, `a//n` or `a/t/n` forms and negative
// (relative) indices, polygons fanned into triangles. Every other statement (vt, vn, o, g, s,
// usemtl, mtllib, l, p) is skipped. The shift sidecar ("<path>.shift.json") is applied as for
// point files. Bad input throws InputError("<path>: line N: <what>").
#pragma once

#include <string>

#include "core/tri_mesh.h"

namespace candi::io {

TriMesh ReadObjMesh(const std::string& path);

}  // namespace candi::io

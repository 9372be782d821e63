// PLY (Stanford polygon format) reading and writing: ascii, binary little and big endian.
//
// Vertex properties: x y z (any numeric type; float or double keeps its precision in
// schema.position_type), red green blue [alpha] (uchar; ushort and float 0-1 are converted),
// nx ny nz, "layer" (integer) and every other numeric vertex property as a scalar field —
// "scalar_<Name>" (CloudCompare) as <Name>, "quality" (MeshLab) as "quality". Vertex list
// properties (OpenMVS's view_indices) and elements other than vertex and face are skipped.
// Faces ("vertex_indices" or "vertex_index" lists) are read by ReadPlyMesh, polygons fanned into
// triangles. The shift is recorded as "comment candi_shift x y z" (and in the sidecar).
// Writers emit double positions when the frame has a shift or the data is double, and write
// scalar fields as "scalar_<Name>" plus "quality" for a field of that name.
// Binary files are read in place (core/mapped_file.h): a Read() call's vertices are decoded in
// parallel blocks straight from the page cache; ascii files through a buffer.
#pragma once

#include <memory>
#include <string>

#include "core/tri_mesh.h"
#include "io/point_file.h"

namespace candi::io {

std::unique_ptr<PointReader> OpenPlyReader(const std::string& path,
                                           const PointReadOptions& options = {});
std::unique_ptr<PointWriter> OpenPlyWriter(const std::string& path, const PointWriteSpec& spec,
                                           const PointWriteOptions& options);

// Reads vertices and faces (polygons fanned into triangles; indices checked against the vertex
// count).
TriMesh ReadPlyMesh(const std::string& path);
void WritePlyMesh(const std::string& path, const TriMesh& mesh,
                  const PointWriteOptions& options = {});

}  // namespace candi::io

#include "mesh/mesh_export.h"

// OpenMesh's IO must be included before any mesh kernel header (the warning: see open_mesh.h).
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <OpenMesh/Core/IO/MeshIO.hh>

#include <algorithm>
#include <cstdio>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/text_format.h"
#include "io/ply/ply_io.h"
#include "io/point_io.h"
#include "io/shift_sidecar.h"
#include "mesh/open_mesh.h"

namespace candi::mesh {

namespace {

std::string Extension(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  std::string ext = dot == std::string::npos ? "" : path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

// OBJ and OFF are written here, not by OpenMesh: its writers go through float (Vec3f), which
// loses the millimetres of large local coordinates. Shortest round-trip digits (text_format.h).
std::string MeshText(const TriMesh& mesh, bool obj) {
  std::string text = obj ? "# candi foundation mesh\n"
                         : "OFF\n" + std::to_string(mesh.vertices.size()) + " " +
                               std::to_string(mesh.faces.size()) + " 0\n";
  if (obj && !mesh.vertices.frame.IsIdentity()) {
    text += "# candi_shift " + mesh.vertices.frame.ToString() + " (world = local + shift)\n";
  }
  char buf[160];
  for (const Eigen::Vector3d& p : mesh.vertices.positions) {
    char* end = buf;
    if (obj) *end++ = 'v', *end++ = ' ';
    for (int k = 0; k < 3; ++k) {
      end = AppendDouble(end, p[k]);
      *end++ = k < 2 ? ' ' : '\n';
    }
    text.append(buf, end);
  }
  const uint32_t base = obj ? 1 : 0;
  for (const auto& f : mesh.faces) {
    text += (obj ? "f " : "3 ") + std::to_string(f[0] + base) + " " + std::to_string(f[1] + base) +
            " " + std::to_string(f[2] + base) + "\n";
  }
  return text;
}

}  // namespace

void WriteMesh(const std::string& path, const TriMesh& mesh) {
  const std::string ext = Extension(path);
  if (ext == ".ply") {
    io::WritePlyMesh(path, mesh);
    return;
  }
  if (ext != ".obj" && ext != ".off") {
    throw InputError(path, "", "unknown mesh extension '" + ext + "' (use .obj, .off or .ply)");
  }
  WriteFileAtomic(path, MeshText(mesh, ext == ".obj"));
  if (!mesh.vertices.frame.IsIdentity()) {
    io::WriteShiftSidecar(path, mesh.vertices.frame);
  } else {
    std::remove(io::ShiftSidecarPath(path).c_str());  // a stale sidecar would mislead
  }
}

TriMesh ReadMesh(const std::string& path) {
  internal::OpenTriMesh om;
  if (!OpenMesh::IO::read_mesh(om, path)) {
    throw InputError(path, "", "OpenMesh could not read the mesh");
  }
  const std::optional<LocalFrame> shift = io::ReadShiftSidecar(path);
  return internal::FromOpenMesh(om, shift ? *shift : LocalFrame());
}

}  // namespace candi::mesh

#include "io/mesh_io.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/text_format.h"
#include "io/obj/obj_mesh.h"
#include "io/ply/ply_io.h"
#include "io/shift_sidecar.h"

namespace candi::io {

namespace {

std::string Extension(const std::string& path) {
  const size_t dot = path.find_last_of('.');
  std::string ext = dot == std::string::npos ? "" : path.substr(dot);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return std::tolower(c); });
  return ext;
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
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
    WritePlyMesh(path, mesh);
    return;
  }
  if (ext != ".obj" && ext != ".off") {
    throw InputError(path, "", "unknown mesh extension '" + ext + "' (use .obj, .off or .ply)");
  }
  WriteFileAtomic(path, MeshText(mesh, ext == ".obj"));
  if (!mesh.vertices.frame.IsIdentity()) {
    WriteShiftSidecar(path, mesh.vertices.frame);
  } else {
    std::remove(ShiftSidecarPath(path).c_str());  // a stale sidecar would mislead
  }
}

// ReadMesh takes the file name's extension (std::filesystem), WriteMesh what follows the path's
// last dot, each as before they met here: they differ only for a dot file or a dot in a folder.
TriMesh ReadMesh(const std::string& path) {
  const std::string ext = Lower(std::filesystem::path(path).extension().string());
  if (ext == ".ply") return ReadPlyMesh(path);
  if (ext == ".obj") return ReadObjMesh(path);
  throw InputError(path, "", "is not a mesh candi reads for C2M (PLY or OBJ)");
}

}  // namespace candi::io

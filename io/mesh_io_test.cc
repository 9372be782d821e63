#include "io/mesh_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>

#include "core/check.h"
#include "io/shift_sidecar.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using testing::FileExists;
using testing::TempDir;

// A tetrahedron whose coordinates need every digit (thirds, sevenths, square roots), its vertices
// in a frame of origin `shift`.
TriMesh Tetrahedron(const Eigen::Vector3d& shift) {
  TriMesh mesh;
  mesh.vertices.Resize(4);
  mesh.vertices.positions = {{1.0 / 3, 2.0 / 7, std::sqrt(2.0)},
                             {-3.25 + std::sqrt(3.0), 0.1, 0.2},
                             {0.125, 2.75 / 3, -1.0 / 7},
                             {std::sqrt(5.0), -0.3, 1.0 / 9}};
  mesh.vertices.frame.origin = shift;
  mesh.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  return mesh;
}

TEST(WriteMesh, ObjTextKeepsEveryDigit) {
  TempDir dir;
  const TriMesh mesh = Tetrahedron({0, 0, 0});
  WriteMesh(dir.File("m.obj"), mesh);
  const std::string text = testing::ReadBytes(dir.File("m.obj"));
  const size_t at = text.find("\nv ");
  ASSERT_NE(at, std::string::npos);
  const char* p = text.c_str() + at + 3;
  char* end = nullptr;
  Eigen::Vector3d first;
  for (int k = 0; k < 3; ++k, p = end) first[k] = std::strtod(p, &end);
  EXPECT_EQ(first, mesh.vertices.positions[0]);
}

TEST(WriteMesh, UnknownExtensionIsAnInputErrorAndNothingIsWritten) {
  TempDir dir;
  EXPECT_THROW(WriteMesh(dir.File("m.stl"), Tetrahedron({0, 0, 0})), InputError);
  EXPECT_FALSE(FileExists(dir.File("m.stl")));
}

TEST(ReadMesh, ReadsWhatWriteMeshWroteInDoubleByTheExtension) {
  TempDir dir;
  for (const Eigen::Vector3d& shift :
       {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(612345, 9123456, 0)}) {
    const TriMesh mesh = Tetrahedron(shift);
    for (const char* name : {"m.ply", "m.obj", "M.OBJ"}) {
      SCOPED_TRACE(name);
      WriteMesh(dir.File(name), mesh);
      const TriMesh back = ReadMesh(dir.File(name));
      EXPECT_EQ(back.vertices.positions, mesh.vertices.positions);
      EXPECT_EQ(back.faces, mesh.faces);
      EXPECT_EQ(back.vertices.frame, mesh.vertices.frame);
      EXPECT_EQ(FileExists(ShiftSidecarPath(dir.File(name))), !mesh.vertices.frame.IsIdentity());
    }
  }
}

TEST(ReadMesh, OtherExtensionsAreAnInputError) {
  TempDir dir;
  WriteMesh(dir.File("m.off"), Tetrahedron({0, 0, 0}));
  EXPECT_THROW(ReadMesh(dir.File("m.off")), InputError);
  EXPECT_THROW(ReadMesh(dir.File("m.stl")), InputError);
}

}  // namespace
}  // namespace candi::io

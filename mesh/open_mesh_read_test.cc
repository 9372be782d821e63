#include "mesh/open_mesh_read.h"

#include <gtest/gtest.h>

#include "io/mesh_io.h"
#include "io/shift_sidecar.h"
#include "mesh/surface_mesh.h"
#include "tests/util/test_util.h"

namespace candi::mesh {
namespace {

using testing::FileExists;
using testing::TempDir;

TriMesh Dome(const Eigen::Vector2d& shift) {
  ProfileOptions po;
  po.samples_per_side = 6;
  RevolveOptions ro;
  ro.angular_steps = 5;
  std::vector<Eigen::Vector2d> pts = {{-3.25, 0.5}, {0.125, 2.75}, {3.5, 0.25}};
  for (auto& p : pts) p += shift;
  return BuildSurfaceMesh({}, RevolveProfile(ro, BuildProfile(po, {pts, false}, {"t", "A"})));
}

TEST(WriteMesh, ObjOffAndPlyRoundTripThroughOpenMesh) {
  TempDir dir;
  for (const Eigen::Vector2d& shift : {Eigen::Vector2d(0, 0), Eigen::Vector2d(612345, 9123456)}) {
    const TriMesh mesh = Dome(shift);
    for (const char* name : {"m.obj", "m.off", "m.ply"}) {
      SCOPED_TRACE(name);
      io::WriteMesh(dir.File(name), mesh);
      const TriMesh back = ReadMesh(dir.File(name));
      ASSERT_EQ(back.vertices.size(), mesh.vertices.size());
      ASSERT_EQ(back.faces, mesh.faces);
      EXPECT_EQ(back.vertices.frame, mesh.vertices.frame);
      // OpenMesh's OBJ/OFF readers parse float; the text itself holds 17 digits
      // (io/mesh_io_test.cc).
      for (size_t i = 0; i < mesh.vertices.size(); ++i) {
        EXPECT_NEAR((back.vertices.positions[i] - mesh.vertices.positions[i]).norm(), 0, 1e-6);
      }
      EXPECT_EQ(FileExists(io::ShiftSidecarPath(dir.File(name))), !mesh.vertices.frame.IsIdentity());
    }
  }
}

}  // namespace
}  // namespace candi::mesh

#include "io/obj/obj_mesh.h"

#include <gtest/gtest.h>

#include "core/check.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using testing::TempDir;
using testing::WriteBytes;

TEST(ObjMeshTest, ReadsDoublesFacesAndColours) {
  TempDir dir;
  WriteBytes(dir.File("m.obj"),
             "# a quad and a triangle at survey coordinates\n"
             "mtllib m.mtl\no thing\n"
             "v 416000.0007 9168000.0003 100.25 1 0 0\n"
             "v 416001.0007 9168000.0003 100.25 0 1 0\n"
             "v 416001.0007 9168001.0003 100.25 0 0 1\n"
             "v 416000.0007 9168001.0003 100.25 1 1 1\n"
             "vt 0 0\nvn 0 0 1\n"
             "f 1/1/1 2/1/1 3/1/1 4/1/1\n"
             "f -4//1 -2//1 -1//1\r\n");
  const TriMesh m = ReadObjMesh(dir.File("m.obj"));
  ASSERT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.vertices.positions[0].x(), 416000.0007);
  EXPECT_EQ(m.vertices.positions[2].y(), 9168001.0003);
  ASSERT_EQ(m.faces.size(), 3u);  // the quad fanned into two
  EXPECT_EQ(m.faces[0], (std::array<uint32_t, 3>{0, 1, 2}));
  EXPECT_EQ(m.faces[1], (std::array<uint32_t, 3>{0, 2, 3}));
  EXPECT_EQ(m.faces[2], (std::array<uint32_t, 3>{0, 2, 3}));
  ASSERT_TRUE(m.vertices.schema.colors);
  EXPECT_EQ(m.vertices.colors[1], (Rgb8{0, 255, 0}));
}

TEST(ObjMeshTest, BadLinesAreNamed) {
  TempDir dir;
  auto error_of = [&](const std::string& text) {
    WriteBytes(dir.File("bad.obj"), text);
    try {
      ReadObjMesh(dir.File("bad.obj"));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of("v 0 0 0\nv 1 0 0\nf 1 2 3\n").find("line 3"), std::string::npos);
  EXPECT_NE(error_of("v 0 0 0\nv 1 0 0\nf 1 2 3\n").find("out of range"), std::string::npos);
  EXPECT_NE(error_of("v 0 zero 0\n").find("'zero' is not a number"), std::string::npos);
  EXPECT_NE(error_of("v 0 0\n").find("needs x y z"), std::string::npos);
  EXPECT_NE(error_of("v 0 0 nan\n").find("not finite"), std::string::npos);
  EXPECT_NE(error_of("v 0 0 0\nv 1 0 0\nf 1 2\n").find("at least 3"), std::string::npos);
  EXPECT_NE(error_of("v 0 0 0\nf 0 1 1\n").find("not a vertex index"), std::string::npos);
  EXPECT_THROW(ReadObjMesh(dir.File("missing.obj")), InputError);
}

}  // namespace
}  // namespace candi::io

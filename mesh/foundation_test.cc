#include "mesh/foundation.h"

#include <gtest/gtest.h>

#include "core/check.h"
#include "tests/util/dxf_text.h"
#include "tests/util/option_check.h"
#include "tests/util/test_util.h"

namespace candi::mesh {
namespace {

using testing::DxfText;
using testing::TempDir;
using V = Eigen::Vector2d;

DxfDrawing Drawing(const TempDir& dir, const DxfText& text) {
  testing::WriteBytes(dir.File("f.dxf"), text.str());
  return ReadDxf({}, dir.File("f.dxf"));
}

TEST(FoundationOptions, DefaultsPass) { EXPECT_NO_THROW(FoundationOptions().Check()); }

TEST(MeshModuleOptions, DefaultsPassCheck) {
  testing::ExpectDefaultsPass<DxfReadOptions, SectionOptions, ProfileOptions, RevolveOptions>();
  EXPECT_NO_THROW(SurfaceMeshOptions().Check());  // flags only: every value is valid
  EXPECT_NO_THROW(MeshCheckOptions().Check());    // flags only: every value is valid
  EXPECT_NO_THROW(FoundationOptions().Check());
}

TEST(BuildLayerSurface, FromDxfLinesToACheckedMesh) {
  TempDir dir;
  DxfText text;
  text.Lines("B", {V(-30, -5), V(-12, 3), V(2, 8), V(15, 2), V(40, -6)});
  FoundationOptions o;
  o.profile.samples_per_side = 60;
  o.revolve.angular_steps = 24;
  const LayerSurface s = BuildLayerSurface(o, Drawing(dir, text), "B");
  EXPECT_EQ(s.mode, RevolveMode::kBlend);
  EXPECT_EQ(s.mesh.faces.size(), 48u + 2 * 58 * 48);
  ASSERT_TRUE(s.checked);
  EXPECT_TRUE(s.check.Ok()) << s.check.Summary();
}

TEST(BuildLayerSurface, MissingLayerNamesTheFileAndListsTheLayers) {
  TempDir dir;
  const DxfDrawing d = Drawing(dir, DxfText().Lines("B", {V(0, 0), V(1, 1), V(2, 0)}));
  try {
    BuildLayerSurface({}, d, "Z");
    FAIL();
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(dir.File("f.dxf") + ": layer 'Z': no such layer"), std::string::npos) << m;
    EXPECT_NE(m.find("(the drawing has: B)"), std::string::npos) << m;
  }
}

TEST(BuildLayerSurface, SelfIntersectingSectionFailsBeforeMeshing) {
  TempDir dir;
  const DxfDrawing d =
      Drawing(dir, DxfText().Polyline("C", {V(-4, 0), V(0, 5), V(4, 0), V(-1, 4), V(-5, -1)}));
  try {
    BuildLayerSurface({}, d, "C");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("layer 'C': the section crosses itself"),
              std::string::npos)
        << e.what();
  }
}

TEST(BuildLayerSurfaces, SameAsOneByOneInOrderAndTheFirstErrorIsRethrown) {
  TempDir dir;
  DxfText text;
  text.Lines("B", {V(-30, -5), V(2, 8), V(40, -6)})
      .Polyline("A", {V(-20, -9), V(3, 1), V(25, -10)})
      .LwPolyline("D", {V(-10, 0), V(0, 4), V(10, 0)});
  const DxfDrawing d = Drawing(dir, text);
  FoundationOptions o;
  o.profile.samples_per_side = 30;
  o.revolve.angular_steps = 12;
  const std::vector<LayerSurface> all = BuildLayerSurfaces(o, d, {"D", "A", "B"}, 2);
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[0].layer, "D");
  EXPECT_EQ(all[0].mode, RevolveMode::kSweep);
  EXPECT_EQ(all[1].mesh.vertices.positions, BuildLayerSurface(o, d, "A").mesh.vertices.positions);
  try {
    BuildLayerSurfaces(o, d, {"A", "X", "Y"});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("layer 'X'"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace candi::mesh

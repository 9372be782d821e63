#include "pipeline/view_orientation.h"

#include <gtest/gtest.h>

#include "core/check.h"
#include "pipeline/render.h"
#include "reconstruction/photogrammetry/mvs/dense_workspace.h"
#include "reconstruction/photogrammetry/scenes/synthetic_views.h"
#include "reconstruction/photogrammetry/scenes/synthetic_workspace.h"
#include "tests/util/test_util.h"

namespace candi::pipeline {
namespace {

namespace pg = photogrammetry;

TEST(ViewOrientation, TheDefaultOrTheCamerasWithTheDirectionsGivenOverThem) {
  const render::Orientation none = ViewOrientation().Resolve();
  EXPECT_EQ(none.up, Eigen::Vector3d::UnitZ());
  EXPECT_FALSE(none.view_dir.has_value());
  ViewOrientation given;
  given.up = Eigen::Vector3d(0, -1, 0);
  EXPECT_EQ(given.Resolve().up, Eigen::Vector3d(0, -1, 0));
  EXPECT_FALSE(given.Resolve().view_dir.has_value());
  // A COLMAP model's cameras, `up` given over theirs and their viewing direction kept.
  testing::TempDir dir;
  pg::SyntheticViewsOptions o;
  o.views = 3;
  o.width = 32;
  o.height = 24;
  o.supersample = 1;
  const std::vector<pg::SyntheticView> views = pg::RenderSyntheticViews(o);
  pg::WriteDenseWorkspace(views, pg::SyntheticSparsePoints(views, 8), dir.File("ws"));
  given.cameras = dir.File("ws/sparse");
  const render::Orientation cameras = OrientationOfCameras(given.cameras);
  const render::Orientation resolved = given.Resolve();
  EXPECT_EQ(resolved.up, Eigen::Vector3d(0, -1, 0));
  ASSERT_TRUE(cameras.view_dir.has_value());
  EXPECT_EQ(resolved.view_dir, cameras.view_dir);
  given.cameras = dir.File("nowhere");
  EXPECT_THROW(given.Resolve(), InputError);
}

}  // namespace
}  // namespace candi::pipeline

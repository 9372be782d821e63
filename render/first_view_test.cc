#include "render/first_view.h"

#include <gtest/gtest.h>

namespace candi::render {
namespace {

TEST(FirstView, KeepsUpUpInSurveyAndColmapFrames) {
  Box3d box;
  box.Extend(Eigen::Vector3d(-1, -2, -3));
  box.Extend(Eigen::Vector3d(4, 5, 6));
  // Survey data (z up): candi render's default view.
  const Camera z = FirstView(box, 320, 240, Orientation());
  const Camera d = FrameBox(box, 320, 240, Eigen::Vector3d(0.45, 0.7, -0.55));
  EXPECT_EQ(z.eye, d.eye);
  EXPECT_EQ(z.up, Eigen::Vector3d::UnitZ());
  // COLMAP's frame (y down): a point further along -y is higher in the image.
  Orientation colmap;
  colmap.up = Eigen::Vector3d(0, -1, 0);
  const Camera c = FirstView(box, 320, 240, colmap);
  const Camera::Projector p = c.MakeProjector();
  double u0, v0, u1, v1, depth;
  ASSERT_TRUE(p.Project(c.target, &u0, &v0, &depth));
  ASSERT_TRUE(p.Project(c.target + Eigen::Vector3d(0, -1, 0), &u1, &v1, &depth));
  EXPECT_LT(v1, v0);
  // And it looks down on the data, as the survey view does: the eye is above the target.
  EXPECT_GT((c.eye - c.target).dot(colmap.up), 0);
  EXPECT_GT((z.eye - z.target).dot(Eigen::Vector3d::UnitZ()), 0);
}

}  // namespace
}  // namespace candi::render

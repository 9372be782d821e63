#include "mesh/revolve.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/check.h"

namespace candi::mesh {
namespace {

using V = Eigen::Vector2d;
const SectionSource kRevolveSource{"drawing.dxf", "A"};

Profile Asymmetric(const V& shift = V::Zero(), int n = 200) {
  std::vector<V> pts = {V(-50, -10), V(-30, 2), V(-5, 9), V(4, 11), V(20, 3), V(60, -12)};
  for (V& p : pts) p += shift;
  ProfileOptions o;
  o.samples_per_side = n;
  return BuildProfile(o, {pts, false}, kRevolveSource);
}

Profile Symmetric() {
  ProfileOptions o;
  o.samples_per_side = 50;
  return BuildProfile(o, {{V(-10, 0), V(-4, 3), V(0, 5), V(4, 3), V(10, 0)}, false}, kRevolveSource);
}

TEST(RevolveOptions, DefaultsPassAndBadValuesThrow) {
  EXPECT_NO_THROW(RevolveOptions().Check());
  RevolveOptions o;
  o.angular_steps = 1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.symmetry_tolerance = -1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  EXPECT_EQ(ParseRevolveMode("sweep"), RevolveMode::kSweep);
  EXPECT_THROW(ParseRevolveMode("spin"), std::invalid_argument);
}

// The must-hold property: theta = 0 and pi reproduce the resampled drawing (1e-9 relative).
void ExpectReproducesDrawing(const Profile& p, const SurfaceGrid& g) {
  const int m = g.columns / 2;
  for (int i = 0; i < g.rings; ++i) {
    const Eigen::Vector3d a = g.At(i, 0), b = g.At(i, m);
    EXPECT_LE((V(a.x(), a.z()) - p.left[i]).norm(), 1e-9 * p.extent) << i;
    EXPECT_LE((V(b.x(), b.z()) - p.right[i]).norm(), 1e-9 * p.extent) << i;
    EXPECT_EQ(a.y(), 0.0);
    EXPECT_EQ(b.y(), 0.0);
  }
}

TEST(RevolveProfile, BlendReproducesTheDrawingAtZeroAndPi) {
  for (const V& shift : {V(0, 0), V(731234.0, 4123456.0)}) {
    const Profile p = Asymmetric(shift);
    RevolveOptions o;
    o.angular_steps = 37;
    const SurfaceGrid g = RevolveProfile(o, p);
    EXPECT_EQ(g.mode, RevolveMode::kBlend) << "auto on an asymmetric layer";
    EXPECT_GT(g.asymmetry, 0.01);
    ExpectReproducesDrawing(p, g);
    EXPECT_EQ(g.frame.origin, Eigen::Vector3d(p.origin.x(), 0, p.origin.y()));
    EXPECT_TRUE(g.apex_top);
  }
}

TEST(RevolveProfile, BlendInterpolatesRadiusAndHeightAndMirrorsTheOtherHalf) {
  const Profile p = Asymmetric();
  RevolveOptions o;
  o.angular_steps = 8;
  const SurfaceGrid g = RevolveProfile(o, p);
  const double axis = p.reference.x();
  const int i = 120, j = 3;
  const double t = 3.0 / 8, theta = M_PI * t;
  const double r = (1 - t) * (axis - p.left[i].x()) + t * (p.right[i].x() - axis);
  const double h = (1 - t) * p.left[i].y() + t * p.right[i].y();
  EXPECT_NEAR(
      (g.At(i, j) - Eigen::Vector3d(axis - r * std::cos(theta), r * std::sin(theta), h)).norm(),
      0.0, 1e-12);
  const Eigen::Vector3d mirror = g.At(i, 16 - j);
  EXPECT_EQ(mirror, Eigen::Vector3d(g.At(i, j).x(), -g.At(i, j).y(), g.At(i, j).z()));
}

TEST(RevolveProfile, AutoSweepsASymmetricLayerAndSaysSo) {
  const Profile p = Symmetric();
  const SurfaceGrid g = RevolveProfile({}, p);
  EXPECT_EQ(g.mode, RevolveMode::kSweep);
  EXPECT_LT(g.asymmetry, 1e-12);
  ExpectReproducesDrawing(p, g);
  for (int j = 0; j < g.columns; ++j) {  // a surface of revolution: same radius all round
    const Eigen::Vector3d q = g.At(20, j) - g.axis_point;
    EXPECT_NEAR(std::hypot(q.x(), q.y()), p.right[20].x() - p.reference.x(), 1e-12);
  }
  RevolveOptions forced;
  forced.mode = RevolveMode::kBlend;
  EXPECT_EQ(RevolveProfile(forced, p).mode, RevolveMode::kBlend);
  forced.mode = RevolveMode::kSweep;
  EXPECT_EQ(RevolveProfile(forced, Asymmetric()).mode, RevolveMode::kSweep);
}

TEST(RevolveProfile, ASideCrossingTheAxisIsAClearError) {
  RevolveOptions o;
  o.axis_x = 4;  // through the peak, as the default: no side crosses
  EXPECT_EQ(RevolveProfile(o, Asymmetric()).positions, RevolveProfile({}, Asymmetric()).positions);
  o.axis_x = 10;  // the right side starts at the peak, x = 4 < 10
  try {
    RevolveProfile(o, Asymmetric());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("right side crosses the axis x = 10"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace candi::mesh

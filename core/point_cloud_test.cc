#include "core/point_cloud.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/check.h"

namespace candi {
namespace {

TEST(PointCloud, SchemaControlsWhichArraysExist) {
  PointCloud cloud;
  cloud.Resize(3);
  PointSchema schema;
  schema.colors = schema.normals = true;
  schema.scalars = {{"intensity", ScalarType::kFloat32}};
  cloud.SetSchema(schema);
  EXPECT_EQ(cloud.colors.size(), 3u);
  EXPECT_EQ(cloud.normals.size(), 3u);
  EXPECT_TRUE(cloud.layers.empty());
  cloud.scalars[0].f32[1] = 5;
  schema.scalars[0].type = ScalarType::kFloat64;  // widening keeps values
  schema.colors = false;
  cloud.SetSchema(schema);
  EXPECT_TRUE(cloud.colors.empty());
  EXPECT_EQ(cloud.scalars[0].f64[1], 5.0);
  EXPECT_NO_THROW(cloud.CheckConsistent());
  cloud.normals.pop_back();
  EXPECT_THROW(cloud.CheckConsistent(), InternalError);
}

TEST(PointCloud, AppendConvertsFramesExactly) {
  PointCloud a, b;
  a.frame.origin = Eigen::Vector3d(500000, 4500000, 0);
  b.frame.origin = Eigen::Vector3d(500100, 4500000, 100);
  a.Resize(1);
  b.Resize(1);
  a.positions[0] = Eigen::Vector3d(0.123, 0.456, 100.789);
  b.positions[0] = Eigen::Vector3d(-99.877, 0.456, 0.789);
  a.Append(b);
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a.WorldPosition(0), a.WorldPosition(1));
}

TEST(PointCloud, RebaseKeepsWorldPositionsAndBoundsFollow) {
  PointCloud c;
  c.Resize(2);
  c.positions = {{500000.123, 4500000.456, 100.789}, {500010.5, 4500020.25, 90.0}};
  const Box3d before = c.WorldBounds();
  LocalFrame f;
  f.origin = Eigen::Vector3d(500000, 4500000, 100);
  c.Rebase(f);
  EXPECT_EQ(c.WorldPosition(0), Eigen::Vector3d(500000.123, 4500000.456, 100.789));
  EXPECT_EQ(c.WorldBounds().min, before.min);
  EXPECT_EQ(c.WorldBounds().max, before.max);
  EXPECT_TRUE(PointCloud{}.WorldBounds().IsEmpty());
}

// Bounds are taken over blocks in parallel: over many blocks they equal one pass's, a NaN
// coordinate counts for nothing (its finite ones still count), and the extremes in the last,
// short block are found.
TEST(PointCloud, BoundsOverManyBlocksSkipNaN) {
  PointCloud c;
  c.Resize(300001);
  for (size_t i = 0; i < c.size(); ++i) {
    const double t = static_cast<double>(i);
    c.positions[i] = Eigen::Vector3d(std::sin(t), std::cos(0.5 * t), 1e-3 * t);
  }
  c.positions[7] = Eigen::Vector3d(std::nan(""), -5, 0);
  c.positions[c.size() - 1].x() = 9;
  Box3d serial;
  for (const Eigen::Vector3d& p : c.positions) {
    for (int k = 0; k < 3; ++k) {
      if (p[k] < serial.min[k]) serial.min[k] = p[k];
      if (p[k] > serial.max[k]) serial.max[k] = p[k];
    }
  }
  const Box3d box = c.LocalBounds();
  EXPECT_EQ(box.min, serial.min);
  EXPECT_EQ(box.max, serial.max);
  EXPECT_EQ(box.min.y(), -5.0);
  EXPECT_EQ(box.max.x(), 9.0);
  EXPECT_EQ(box.max.z(), 300.0);
}

TEST(PointCloud, ScalarFieldsAreUniqueByName) {
  PointCloud c;
  c.Resize(2);
  EXPECT_EQ(c.AddScalarField("a"), 0);
  EXPECT_THROW(c.AddScalarField("a"), InternalError);
  EXPECT_EQ(c.FindScalar("a")->size(), 2u);
  EXPECT_EQ(c.FindScalar("b"), nullptr);
}

}  // namespace
}  // namespace candi

#include "io/layer_clouds.h"

#include <gtest/gtest.h>

#include "core/check.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using testing::FileExists;
using testing::TempDir;

PointCloud Layer(size_t n, const Eigen::Vector3d& origin, uint16_t id) {
  PointCloud c;
  PointSchema schema;
  schema.colors = schema.layers = schema.normals = true;
  c.SetSchema(schema);
  c.frame.origin = origin;
  c.Resize(n);
  for (size_t i = 0; i < n; ++i) {
    c.positions[i] = Eigen::Vector3d(0.1 * i + 1e-3 / 3, -0.7 * i, 1.0 / (i + 3));
    c.normals[i] = Eigen::Vector3f(0, 0, 1);
    c.colors[i] = Rgb8{static_cast<uint8_t>(i), 2, 3};
    c.layers[i] = id;
  }
  return c;
}

// Streaming the layers through one writer gives what merging them with Append and writing the
// merged cloud gives: same positions to the bit (other frames re-expressed the same way), same
// attributes, the layer-name comment, and the first cloud's frame.
TEST(WriteLayerClouds, EqualsTheAppendedCloudAndNamesTheLayers) {
  TempDir dir;
  const std::vector<PointCloud> clouds = {Layer(70000, {500000.25, 4e6, 100}, 0),
                                          Layer(3, {500010.5, 4e6 - 3.1, 90}, 1),
                                          Layer(0, {1, 2, 3}, 2)};
  WriteLayerClouds(dir.File("l.ply"), clouds, {"A", "B", "C"});
  PointCloud merged = clouds[0];
  merged.Append(clouds[1]);
  merged.Append(clouds[2]);
  const PointCloud back = io::ReadPointCloud(dir.File("l.ply"));
  EXPECT_EQ(back.frame, clouds[0].frame);
  EXPECT_EQ(back.positions, merged.positions);
  EXPECT_EQ(back.layers, merged.layers);
  EXPECT_EQ(back.colors, merged.colors);
  EXPECT_EQ(back.normals, merged.normals);
  bool named = false;
  for (const std::string& c : back.meta.comments) named |= c == "candi_layers 0=A 1=B 2=C";
  EXPECT_TRUE(named);
  EXPECT_THROW(WriteLayerClouds(dir.File("m.ply"), clouds, {"A"}), InternalError);
  EXPECT_FALSE(FileExists(dir.File("m.ply")));
}

}  // namespace
}  // namespace candi::io

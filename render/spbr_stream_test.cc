#include "render/spbr_stream.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/check.h"
#include "render/splat_cloud.h"
#include "render/synthetic_scene.h"

namespace candi::render {
namespace {

struct Scene {
  PointCloud cloud;
  LocalFrame frame;
  Camera camera;  // in `frame`
};

Scene MakeScene(uint64_t n) {
  Scene s;
  s.cloud = LayeredSheets(n, 3, 5);
  const Box3d world = s.cloud.WorldBounds();
  s.frame = RenderFrameFor(world);
  s.camera = ObliqueView(world.Translated(-s.frame.origin), 96, 80);
  return s;
}

PointCloud Slice(const PointCloud& cloud, size_t begin, size_t end) {
  PointCloud part;
  part.SetSchema(cloud.schema);
  part.frame = cloud.frame;
  for (size_t i = begin; i < end; ++i) part.AppendFrom(cloud, i);
  return part;
}

// Feeds `cloud` in chunks of `chunk` points, every pass.
SpbrResult Stream(const Scene& s, int L, uint64_t seed, size_t chunk, int threads, uint64_t budget) {
  SpbrStreamOptions o;
  o.repeat_level = L;
  o.seed = seed;
  o.threads = threads;
  o.memory_budget = budget;
  SpbrStreamRenderer renderer(o, s.camera, s.frame);
  for (int pass = 0; pass < renderer.passes(); ++pass) {
    renderer.BeginPass(pass);
    for (size_t begin = 0; begin < s.cloud.size(); begin += chunk) {
      renderer.Add(Slice(s.cloud, begin, std::min(s.cloud.size(), begin + chunk)));
    }
    renderer.EndPass();
  }
  return renderer.Finish();
}

constexpr uint64_t kOneFrame = 96 * 80 * 8;  // bytes of one ensemble's z-buffer

TEST(SpbrStream, SameImageForAnyChunkSizeThreadCountAndBudget) {
  const Scene s = MakeScene(60000);
  const SpbrResult base = Stream(s, 16, 3, 60000, 1, uint64_t{1} << 30);
  EXPECT_EQ(base.ensembles, 16);
  EXPECT_EQ(base.copies, 60000u);
  const SpbrResult chunked = Stream(s, 16, 3, 777, 2, uint64_t{1} << 30);
  EXPECT_TRUE(base.sums == chunked.sums) << "chunk size or threads changed the image";
  // A budget of 3 frames: 6 passes, each holding 3 ensembles (the last 1).
  SpbrStreamOptions o;
  o.repeat_level = 16;
  o.memory_budget = 3 * kOneFrame;
  EXPECT_EQ(SpbrStreamRenderer(o, s.camera, s.frame).passes(), 6);
  const SpbrResult passes = Stream(s, 16, 3, 5000, 2, 3 * kOneFrame);
  EXPECT_TRUE(base.sums == passes.sums) << "splitting the ensembles over passes changed the image";
  const SpbrResult other_seed = Stream(s, 16, 4, 60000, 1, uint64_t{1} << 30);
  EXPECT_FALSE(base.sums == other_seed.sums);
}

SpbrResult InMemory(const Scene& s, int L, uint64_t seed) {
  SplatCloudOptions build;
  build.repeat_level = L;
  build.seed = seed;
  const SplatCloud splats = BuildSplatCloud(build, {&s.cloud});
  Camera camera = s.camera;  // the splat cloud's frame may differ from s.frame
  camera.eye += s.frame.origin - splats.frame.origin;
  camera.target += s.frame.origin - splats.frame.origin;
  return RenderSpbr(SpbrOptions{}, camera, splats);
}

double Rmse(const SpbrResult& x, const SpbrResult& y) {
  const ImageF a = AverageImage(x, {0, 0, 0}), b = AverageImage(y, {0, 0, 0});
  double sum = 0;
  for (size_t i = 0; i < a.values().size(); ++i) sum += std::pow(a.values()[i] - b.values()[i], 2);
  return std::sqrt(sum / a.values().size());
}

// Streamed and in-memory renders differ only by the noise of SPBR: no more than two in-memory
// renders with different seeds.
TEST(SpbrStream, MatchesTheInMemoryRendererStatistically) {
  const Scene s = MakeScene(200000);
  const SpbrResult streamed = Stream(s, 64, 9, 50000, 0, uint64_t{1} << 30);
  const SpbrResult memory = InMemory(s, 64, 9), memory_other_seed = InMemory(s, 64, 10);
  const double noise = Rmse(memory, memory_other_seed);
  EXPECT_GT(noise, 0.5) << "the scene is visible and noisy";
  EXPECT_LT(Rmse(streamed, memory), 1.15 * noise);
}

TEST(SpbrStream, NanPositionsAreAnErrorAndEmptyChunksAreFine) {
  Scene s = MakeScene(1000);
  SpbrStreamOptions o;
  o.repeat_level = 4;
  SpbrStreamRenderer renderer(o, s.camera, s.frame);
  renderer.BeginPass(0);
  renderer.Add(PointCloud());
  s.cloud.positions[500].y() = std::numeric_limits<double>::quiet_NaN();
  try {
    renderer.Add(s.cloud);
    FAIL() << "NaN accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("500"), std::string::npos) << e.what();
  }
}

TEST(SpbrStream, BadOptionsNameTheField) {
  SpbrStreamOptions o;
  o.repeat_level = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.point_size = 100;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.memory_budget = kOneFrame - 1;
  const Scene s = MakeScene(10);
  try {
    SpbrStreamRenderer renderer(o, s.camera, s.frame);
    FAIL() << "a budget below one frame accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("memory_budget"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace candi::render

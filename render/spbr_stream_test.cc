#include "render/spbr_stream.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "core/check.h"
#include "core/mapped_file.h"
#include "io/point_io.h"
#include "render/splat_cloud.h"
#include "render/synthetic_scene.h"
#include "tests/util/test_util.h"

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
SpbrResult Stream(const Scene& s, int L, uint64_t seed, size_t chunk, int threads, uint64_t budget,
                  uint64_t expected_points = 0, double point_size = 1.0) {
  SpbrStreamOptions o;
  o.spbr.repeat_level = L;
  o.spbr.seed = seed;
  o.threads = threads;
  o.memory_budget = budget;
  o.expected_points = expected_points;
  o.spbr.point_size = point_size;
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
  o.spbr.repeat_level = 16;
  o.memory_budget = 3 * kOneFrame;
  EXPECT_EQ(SpbrStreamRenderer(o, s.camera, s.frame).passes(), 6);
  const SpbrResult passes = Stream(s, 16, 3, 5000, 2, 3 * kOneFrame);
  EXPECT_TRUE(base.sums == passes.sums) << "splitting the ensembles over passes changed the image";
  const SpbrResult other_seed = Stream(s, 16, 4, 60000, 1, uint64_t{1} << 30);
  EXPECT_FALSE(base.sums == other_seed.sums);
}

// The points with a multiplicity of one each: staged by the serial path for multiplicities,
// point by point, where points without one are staged by parallel blocks.
TEST(SpbrStream, ParallelStagingGivesTheSerialImage) {
  const Scene s = MakeScene(70000);
  Scene ones = s;
  ones.cloud.AddScalarField(kMultiplicityField);
  for (size_t i = 0; i < ones.cloud.size(); ++i) ones.cloud.FindScalar(kMultiplicityField)->Set(i, 1.0);
  const SpbrResult serial = Stream(ones, 16, 5, 70000, 1, uint64_t{1} << 30);
  for (int threads : {1, 2}) {
    for (size_t chunk : {size_t{70000}, size_t{16385}, size_t{999}}) {
      EXPECT_TRUE(Stream(s, 16, 5, chunk, threads, uint64_t{1} << 30).sums == serial.sums)
          << threads << " threads, chunks of " << chunk;
    }
  }
  EXPECT_TRUE(Stream(s, 16, 5, 4000, 2, 3 * kOneFrame).sums == serial.sums) << "6 passes";
  // 10^5 ensembles resident (a 6 x 4 image): blocks grow so that their counts stay bounded.
  Scene tiny = MakeScene(700000), tiny_ones = tiny;
  tiny.camera.width = tiny_ones.camera.width = 6;
  tiny.camera.height = tiny_ones.camera.height = 4;
  tiny_ones.cloud.AddScalarField(kMultiplicityField);
  for (size_t i = 0; i < tiny_ones.cloud.size(); ++i) tiny_ones.cloud.FindScalar(kMultiplicityField)->Set(i, 1.0);
  const SpbrResult tiny_serial = Stream(tiny_ones, 100000, 5, 700000, 1, uint64_t{1} << 30);
  uint64_t hits = 0;
  for (size_t p = 0; p < 24; ++p) hits += tiny_serial.sums.sums[4 * p + 3];
  EXPECT_GT(hits, 100000u) << "the tiny image shows the points";
  EXPECT_TRUE(Stream(tiny, 100000, 5, 700000, 2, uint64_t{1} << 30).sums == tiny_serial.sums);
}

// Points gathered by ensemble and drawn at the end of the pass (few points expected) give the
// image of resident z-buffers, with and without multiplicities, point sizes, on 1 and 2 threads.
TEST(SpbrStream, GatheringFewPointsGivesTheResidentImage) {
  const Scene s = MakeScene(40000);
  Scene ones = s;
  ones.cloud.AddScalarField(kMultiplicityField);
  for (size_t i = 0; i < ones.cloud.size(); ++i) ones.cloud.FindScalar(kMultiplicityField)->Set(i, i % 3 == 0 ? 2.0 : 1.0);
  for (double size : {1.0, 2.5}) {
    for (const Scene* scene : {&s, static_cast<const Scene*>(&ones)}) {
      const SpbrResult resident = Stream(*scene, 16, 7, 40000, 1, uint64_t{1} << 30, 0, size);
      for (int threads : {1, 2}) {
        const SpbrResult gathered = Stream(*scene, 16, 7, 3333, threads, uint64_t{1} << 30, 40000, size);
        EXPECT_TRUE(gathered.sums == resident.sums) << "size " << size << ", " << threads << " threads";
        EXPECT_EQ(gathered.copies, resident.copies);
        EXPECT_EQ(gathered.first_ensemble_grey, resident.first_ensemble_grey);
      }
    }
  }
  // Gathering holds no more than the z-buffers would: 40000 points at 16 bytes need 640 KB, so a
  // budget of 3 frames (184 KB) keeps 6 passes of resident z-buffers; 10^4 points (160 KB) gather.
  SpbrStreamOptions o;
  o.spbr.repeat_level = 16;
  o.memory_budget = 3 * kOneFrame;
  o.expected_points = 40000;
  EXPECT_EQ(SpbrStreamRenderer(o, s.camera, s.frame).passes(), 6);
  o.expected_points = 10000;
  EXPECT_EQ(SpbrStreamRenderer(o, s.camera, s.frame).passes(), 1);
  // More points than expected: still the same image.
  EXPECT_TRUE(Stream(s, 16, 7, 5000, 2, uint64_t{1} << 30, 100).sums == Stream(s, 16, 7, 5000, 2, uint64_t{1} << 30).sums);
}

// The image of a file's records read in place (AddRecords) is the image of its reader's chunks,
// for float and double PLY and for LAS, on 1 and 2 threads, in one pass or several, with
// one-pixel points and larger ones.
TEST(SpbrStream, RecordsInPlaceGiveTheImageOfTheReadersChunks) {
  candi::testing::TempDir dir;
  Scene s = MakeScene(50000);
  s.cloud.frame.origin += Eigen::Vector3d(416000, 9168000, 200);  // survey coordinates
  s.frame.origin += Eigen::Vector3d(416000, 9168000, 200);
  struct File {
    std::string name;
    io::PositionPrecision precision;
    io::PointRecordLayout::Coordinates coordinates;
  };
  using C = io::PointRecordLayout::Coordinates;
  for (const File& f : {File{"f.ply", io::PositionPrecision::kFloat32, C::kFloat32},
                        File{"d.ply", io::PositionPrecision::kFloat64, C::kFloat64},
                        File{"p.las", io::PositionPrecision::kAuto, C::kLasInt32}}) {
    const std::string path = dir.File(f.name);
    io::PointWriteOptions w;
    w.precision = f.precision;
    io::WritePointCloud(path, s.cloud, w);
    io::PointReadOptions read;
    read.scalar_fields = false;
    const std::optional<io::PointRecordLayout> layout = io::OpenPointReader(path, read)->record_layout();
    ASSERT_TRUE(layout) << f.name;
    EXPECT_EQ(layout->coordinates, f.coordinates) << f.name;
    for (double size : {1.0, 2.5}) {
      for (int threads : {1, 2}) {
        for (uint64_t budget : {uint64_t{1} << 30, 3 * kOneFrame, uint64_t{0}}) {
          SpbrStreamOptions o;
          o.spbr.repeat_level = 8;
          o.spbr.seed = 11;
          o.threads = threads;
          o.spbr.point_size = size;
          o.memory_budget = budget > 0 ? budget : uint64_t{1} << 30;
          SpbrStreamOptions gathering = o;  // budget 0: the records gathered, the chunks resident
          if (budget == 0) gathering.expected_points = 50000;
          SpbrStreamRenderer chunks(o, s.camera, s.frame), records(gathering, s.camera, s.frame);
          const MappedFile map(path);
          for (int pass = 0; pass < chunks.passes(); ++pass) {
            chunks.BeginPass(pass);
            auto r = io::OpenPointReader(path, read);
            PointCloud chunk;
            while (r->Read(7000, &chunk) > 0) chunks.Add(chunk);
            chunks.EndPass();
            records.BeginPass(pass);
            for (uint64_t at = 0; at < layout->count; at += 12345) {
              const size_t n = static_cast<size_t>(std::min<uint64_t>(12345, layout->count - at));
              records.AddRecords(map.data() + layout->first_byte + at * layout->stride, *layout, r->info().frame.origin, n);
            }
            records.EndPass();
          }
          const SpbrResult a = chunks.Finish(), b = records.Finish();
          EXPECT_EQ(a.copies, 50000u);
          EXPECT_EQ(b.copies, 50000u);
          EXPECT_TRUE(a.sums == b.sums) << f.name << ", point size " << size << ", " << threads << " threads, budget "
                                        << budget;
        }
      }
    }
  }
}

SpbrResult InMemory(const Scene& s, int L, uint64_t seed) {
  SplatCloudOptions build;
  build.spbr.repeat_level = L;
  build.spbr.seed = seed;
  const SplatCloud splats = BuildSplatCloud(build, {&s.cloud});
  Camera camera = s.camera;  // the splat cloud's frame may differ from s.frame
  camera.eye += s.frame.origin - splats.frame.origin;
  camera.target += s.frame.origin - splats.frame.origin;
  return RenderSpbr(SpbrOptions{}, camera, splats);
}

double ResultRmse(const SpbrResult& x, const SpbrResult& y) {
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
  const double noise = ResultRmse(memory, memory_other_seed);
  EXPECT_GT(noise, 0.5) << "the scene is visible and noisy";
  EXPECT_LT(ResultRmse(streamed, memory), 1.15 * noise);
}

TEST(SpbrStream, NanPositionsAreAnErrorAndEmptyChunksAreFine) {
  Scene s = MakeScene(1000);
  SpbrStreamOptions o;
  o.spbr.repeat_level = 4;
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
  // Records in place: the first bad point of the stream, whichever block finds it.
  std::vector<float> records(3 * 40000, 1.0f);
  records[3 * 33333 + 2] = std::numeric_limits<float>::infinity();
  records[3 * 35000] = std::numeric_limits<float>::quiet_NaN();
  io::PointRecordLayout layout;
  layout.stride = 12;
  layout.xyz[1] = 4, layout.xyz[2] = 8;
  layout.count = 40000;
  SpbrStreamOptions two = o;
  two.threads = 2;
  SpbrStreamRenderer in_place(two, s.camera, s.frame);
  in_place.BeginPass(0);
  in_place.AddRecords(reinterpret_cast<const uint8_t*>(records.data()), layout, s.frame.origin, 100);
  try {
    in_place.AddRecords(reinterpret_cast<const uint8_t*>(records.data()), layout, s.frame.origin, 40000);
    FAIL() << "infinity accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("point 33433 "), std::string::npos) << e.what();  // 100 came first
  }
}

TEST(SpbrStream, BadOptionsNameTheField) {
  SpbrStreamOptions o;
  o.spbr.repeat_level = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.spbr.point_size = 100;
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

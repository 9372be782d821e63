// Rendering from a render archive: the archive renderer against a plain reference, bit for bit,
// with clipping, layer fractions, threads, passes, budgets and cancelling. (Packing and the
// manifest are archive_test.cc.)
#include "render/archive.h"
#include "render/archive_clip.h"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cmath>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/rng.h"
#include "io/point_io.h"
#include "render/archive_pack.h"
#include "render/archive_render.h"
#include "render/spbr_stream.h"
#include "render/splat_cloud.h"
#include "render/splat_kernel.h"
#include "render/synthetic_scene.h"
#include "tests/util/test_util.h"

namespace candi::render {
namespace {

using candi::testing::TempDir;

// ---- rendering ------------------------------------------------------------------------------

// The reference: for each ensemble, every chunk's runs (EnsembleSlices) dequantized, in float,
// through the plain kernel (SplatPoints) into a whole-image z-buffer; no passes, threads, groups
// or replicas.
SpbrResult Reference(const Archive& a, const Camera& camera, int L, uint64_t seed, double point_size,
                     const std::vector<double>& fractions = {}, const ClipRegion& clip = {}) {
  const ArchiveManifest& m = a.manifest();
  const Camera::Projector p = camera.MakeProjector();
  KernelTransform t;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) t.a[3 * r + c] = static_cast<float>(p.rotation(r, c));
  }
  Eigen::Vector3d b = -(p.rotation * p.eye);
  b.z() += OrthographicDepthOffset(p, m.bounds);
  for (int r = 0; r < 3; ++r) t.b[r] = static_cast<float>(b[r]);
  const KernelProjection kp{static_cast<float>(p.focal), static_cast<float>(p.cx), static_cast<float>(p.cy),
                            p.perspective ? static_cast<float>(p.near) : -std::numeric_limits<float>::infinity(),
                            p.perspective, camera.width, camera.height, 0, camera.height};
  SpbrResult result;
  result.sums = Accumulator(camera.width, camera.height);
  result.repeat_level = result.ensembles = L;
  result.seed = seed;
  BandBuffer band;
  band.Reset(camera.width, camera.height);
  PointCloud chunk;
  for (int e = 0; e < L; ++e) {
    for (size_t k = 0; k < m.chunks.size(); ++k) {
      const ArchiveChunk& c = m.chunks[k];
      std::vector<PointRun> runs;
      EnsembleSlices(c.count, c.first, L, seed, e, fractions.empty() ? 1.0 : fractions[c.layer], &runs);
      if (runs.empty()) continue;
      a.ReadChunk(k, &chunk);
      for (const PointRun& run : runs) {
        std::vector<float> x, y, z;
        std::vector<uint32_t> colors;
        std::vector<uint64_t> index;
        for (uint64_t i = run.begin; i < run.end; ++i) {
          if (!clip.Contains(chunk.positions[i])) continue;
          index.push_back(c.first + i);
          x.push_back(static_cast<float>(chunk.positions[i].x()));
          y.push_back(static_cast<float>(chunk.positions[i].y()));
          z.push_back(static_cast<float>(chunk.positions[i].z()));
          const Rgb8 rgb = chunk.colors[i];
          colors.push_back(uint32_t{rgb.r} << 16 | uint32_t{rgb.g} << 8 | rgb.b);
        }
        if (point_size == 1.0) {
          SplatPoints(t, kp, x.data(), y.data(), z.data(), colors.data(), x.size(), &band);
        } else {
          for (size_t i = 0; i < x.size(); ++i) {
            SplatPointsSized(t, kp, &x[i], &y[i], &z[i], &colors[i], 1, {point_size, seed, index[i]}, &band);
          }
        }
        result.copies += x.size();
      }
    }
    GreyHistogram grey{};
    band.DrainInto(&result.sums, e == 0 ? &grey : nullptr);
    if (e == 0) std::copy(grey.begin(), grey.end(), result.first_ensemble_grey.begin());
  }
  return result;
}

class ArchiveRender : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir;
    PackOptions o;
    o.chunk_points = 1024;
    // Two layers, so that per-layer fractions are covered.
    PackArchive(o, {PackInputFromGenerator("scene", 40000, 20000,
                                           [](uint64_t k, uint64_t n) { return TerracedSolid(n, 100 + k); }),
                    PackInputFromGenerator("more", 20000, 20000,
                                           [](uint64_t k, uint64_t n) { return TerracedSolid(n, 200 + k); })},
                dir_->path() + "/arc");
    archive_ = new Archive(dir_->path() + "/arc");
  }
  static void TearDownTestSuite() {
    delete archive_;
    delete dir_;
  }
  static TempDir* dir_;
  static Archive* archive_;
};
TempDir* ArchiveRender::dir_ = nullptr;
Archive* ArchiveRender::archive_ = nullptr;

// Clipping (a box and a slanted half-space): chunks outside are skipped, chunks inside drawn
// whole, the cut ones point by point; the image is the reference's that skips the clipped points.
TEST_F(ArchiveRender, ClippedEqualsTheReferenceBitForBit) {
  const Box3d bounds = archive_->manifest().bounds;
  Box3d inner{bounds.min + 0.2 * bounds.Extent(), bounds.max - 0.3 * bounds.Extent()};
  ClipRegion clip = ClipRegion::Box(inner);
  clip.planes.push_back({bounds.Center(), Eigen::Vector3d(1, -0.5, 0.3)});
  for (Projection projection : {Projection::kPerspective, Projection::kOrthographic}) {
    Camera camera = ObliqueView(bounds, 120, 90);
    camera.projection = projection;
    for (double size : {1.0, 2.5}) {
      const SpbrResult ref = Reference(*archive_, camera, 8, 5, size, {0.6, 1.0}, clip);
      ArchiveRenderOptions o;
      o.spbr.repeat_level = 8;
      o.spbr.seed = 5;
      o.spbr.point_size = size;
      o.threads = 2;
      o.layer_fraction = {0.6, 1.0};
      o.clip = clip;
      ArchiveRenderStats stats;
      const SpbrResult r = RenderArchive(o, camera, *archive_, nullptr, &stats);
      EXPECT_TRUE(r.sums == ref.sums) << size;
      EXPECT_EQ(r.copies, ref.copies);
      EXPECT_GT(ref.copies, 1000u);
      EXPECT_LT(ref.copies, 30000u);
      EXPECT_GT(stats.chunks_clipped, 0u);
      EXPECT_LT(stats.chunks_visible, stats.chunks);  // chunks wholly outside were not read
    }
  }
  // A region holding everything gives the unclipped image.
  Camera camera = ObliqueView(bounds, 120, 90);
  ArchiveRenderOptions o;
  o.spbr.repeat_level = 4;
  const SpbrResult plain = RenderArchive(o, camera, *archive_);
  o.clip = ClipRegion::Box(Box3d{(bounds.min.array() - 1).matrix(), (bounds.max.array() + 1).matrix()});
  EXPECT_TRUE(RenderArchive(o, camera, *archive_).sums == plain.sums);
  // A region holding nothing gives an empty image.
  o.clip = ClipRegion{{{bounds.max + Eigen::Vector3d::Ones(), Eigen::Vector3d::UnitX()}}};
  EXPECT_EQ(RenderArchive(o, camera, *archive_).copies, 0u);
  // Bad regions are refused naming the field.
  o.clip = ClipRegion{{{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()}}};
  EXPECT_THROW(RenderArchive(o, camera, *archive_), std::invalid_argument);
}

// A slab (and a union of two) reads only the chunks it crosses and keeps exactly the points a
// filter of every point keeps, in chunk order, whatever the thread count.
TEST_F(ArchiveRender, ReadClippedKeepsTheRegionsPointsReadingOnlyCrossedChunks) {
  const Box3d bounds = archive_->manifest().bounds;
  const ClipRegion a = ClipRegion::Slab(bounds.Center(), Eigen::Vector3d(1, 0.2, 0), 0.05 * bounds.Extent().x());
  const ClipRegion b = ClipRegion::Slab(bounds.min + 0.2 * bounds.Extent(), Eigen::Vector3d(0, 1, 0), 0.1);
  const PointCloud all = archive_->ReadAll();
  for (const std::vector<ClipRegion>& regions : {std::vector<ClipRegion>{a}, std::vector<ClipRegion>{a, b}}) {
    std::vector<Eigen::Vector3d> expected;
    std::vector<uint8_t> expected_region;
    for (const Eigen::Vector3d& x : all.positions) {
      for (size_t r = 0; r < regions.size(); ++r) {
        if (regions[r].Contains(x)) {
          expected.push_back(x);
          expected_region.push_back(static_cast<uint8_t>(r));
          break;
        }
      }
    }
    uint64_t needed = 0;  // chunks holding a kept point
    PointCloud chunk;
    for (size_t k = 0; k < archive_->manifest().chunks.size(); ++k) {
      archive_->ReadChunk(k, &chunk);
      bool any = false;
      for (const Eigen::Vector3d& x : chunk.positions) {
        for (const ClipRegion& r : regions) any |= r.Contains(x);
      }
      needed += any ? 1 : 0;
    }
    for (int threads : {1, 2}) {
      ClippedReadOptions o;
      o.threads = threads;
      const ClippedPoints got = ReadClipped(o, *archive_, regions);
      ASSERT_EQ(got.cloud.positions, expected) << regions.size() << " regions, " << threads << " threads";
      EXPECT_EQ(got.region, expected_region);
      EXPECT_GT(expected.size(), 100u);
      EXPECT_LT(got.chunks_read, got.chunks) << "a thin slab does not cross every chunk";
      EXPECT_GE(got.chunks_read, needed);
      ASSERT_EQ(got.cloud.layers.size(), expected.size());
    }
  }
  // A layer left out is not read.
  ClippedReadOptions o;
  o.layers = {1, 0};
  const ClippedPoints first = ReadClipped(o, *archive_, {a});
  for (uint16_t l : first.cloud.layers) ASSERT_EQ(l, 0);
  // Nothing inside: nothing read.
  const ClippedPoints none = ReadClipped({}, *archive_, {ClipRegion::Slab(bounds.max * 3 + Eigen::Vector3d::Ones(), Eigen::Vector3d::UnitZ(), 1)});
  EXPECT_EQ(none.chunks_read, 0u);
  EXPECT_TRUE(none.cloud.empty());
}

TEST_F(ArchiveRender, EqualsAPlainReferenceBitForBit) {
  ASSERT_EQ(archive_->manifest().layers.size(), 2u);
  for (Projection projection : {Projection::kPerspective, Projection::kOrthographic}) {
    Camera camera = ObliqueView(archive_->manifest().bounds, 120, 90);
    camera.projection = projection;
    for (double size : {1.0, 2.5}) {
      for (const std::vector<double>& fractions : {std::vector<double>{}, std::vector<double>{0.37, 2.6}}) {
        const SpbrResult ref = Reference(*archive_, camera, 12, 7, size, fractions);
        ArchiveRenderOptions o;
        o.spbr.repeat_level = 12;
        o.spbr.seed = 7;
        o.spbr.point_size = size;
        o.threads = 2;
        o.layer_fraction = fractions;
        const SpbrResult one = RenderArchive(o, camera, *archive_);
        const std::string what = "size " + std::to_string(size) + ", " + std::to_string(fractions.size()) +
                                 " fractions, projection " + std::to_string(static_cast<int>(projection));
        EXPECT_TRUE(one.sums == ref.sums) << what;
        EXPECT_EQ(one.first_ensemble_grey, ref.first_ensemble_grey) << what;
        EXPECT_EQ(one.copies, ref.copies) << what;
        if (fractions.empty()) {
          EXPECT_EQ(ref.copies, 60000u);  // every point in one ensemble
        }
        // Small budgets: several passes, one chunk per batch, one thread: same sums.
        o.memory_budget = 12 * 120 * 90 * 5;
        o.chunk_budget = 1024 * (kChunkBytesPerPoint + 8);
        o.threads = 1;
        ArchiveRenderStats stats;
        const SpbrResult small = RenderArchive(o, camera, *archive_, nullptr, &stats);
        EXPECT_EQ(stats.passes, 3);
        EXPECT_TRUE(small.sums == ref.sums) << what;
        // A different seed gives a different image (the test can fail).
        o.spbr.seed = 8;
        EXPECT_FALSE(RenderArchive(o, camera, *archive_).sums == ref.sums) << what;
      }
    }
  }
}

TEST_F(ArchiveRender, LayerFractionsDrawTheirShareAndZeroReadsNothing) {
  const Camera camera = ObliqueView(archive_->manifest().bounds, 64, 48);
  const ArchiveManifest& m = archive_->manifest();
  ArchiveRenderOptions o;
  o.spbr.repeat_level = 50;
  o.layer_fraction = {0.5, 0};
  ArchiveRenderStats stats;
  const SpbrResult half = RenderArchive(o, camera, *archive_, nullptr, &stats);
  uint64_t layer0_chunks = 0;
  for (const ArchiveChunk& c : m.chunks) layer0_chunks += c.layer == 0;
  EXPECT_LE(stats.chunks_visible, layer0_chunks);  // the hidden layer's chunks are not read
  // Half of layer 0's 40000 points, to within the stochastic rounding of each slice.
  EXPECT_NEAR(static_cast<double>(half.copies), 20000.0, 400.0);
  o.layer_fraction = {3.0, 1.0};
  EXPECT_EQ(RenderArchive(o, camera, *archive_).copies, 3 * 40000u + 20000u);
  o.layer_fraction = {1.0};
  EXPECT_THROW(RenderArchive(o, camera, *archive_), std::invalid_argument);
  o.layer_fraction = {1.0, -0.5};
  EXPECT_THROW(RenderArchive(o, camera, *archive_), std::invalid_argument);
}

TEST(ArchiveSlices, EveryPointInExactlyOneEnsembleAndPrefixesAreFractions) {
  for (uint64_t n : {1u, 7u, 100u, 65536u}) {
    for (int L : {1, 3, 100, 1000}) {
      std::vector<int> hits(n, 0);
      std::vector<PointRun> runs;
      for (int e = 0; e < L; ++e) {
        runs.clear();
        EnsembleSlices(n, 12345, L, 9, e, 1.0, &runs);
        ASSERT_LE(runs.size(), 1u);
        for (const PointRun& r : runs) {
          for (uint64_t i = r.begin; i < r.end; ++i) ++hits[i];
        }
      }
      for (uint64_t i = 0; i < n; ++i) ASSERT_EQ(hits[i], 1) << "n " << n << " L " << L << " point " << i;
    }
  }
  // The seed rotates which slice an ensemble gets.
  std::vector<PointRun> a, b;
  EnsembleSlices(1000, 0, 10, 1, 0, 1.0, &a);
  EnsembleSlices(1000, 0, 10, 2, 0, 1.0, &b);
  ASSERT_EQ(a.size(), 1u);
  ASSERT_EQ(b.size(), 1u);
  int differ = 0;
  for (uint64_t seed = 2; seed < 12; ++seed) {
    b.clear();
    EnsembleSlices(1000, 0, 10, seed, 0, 1.0, &b);
    differ += b[0].begin != a[0].begin;
  }
  EXPECT_GE(differ, 5);
  // Fraction 2.5: each ensemble takes two whole slices and half of a third.
  a.clear();
  EnsembleSlices(1000, 0, 10, 1, 3, 2.5, &a);
  ASSERT_EQ(a.size(), 3u);
  EXPECT_EQ(a[0].end - a[0].begin, 100u);
  EXPECT_EQ(a[1].end - a[1].begin, 100u);
  EXPECT_EQ(a[2].end - a[2].begin, 50u);
  // Fraction 0: nothing.
  a.clear();
  EnsembleSlices(1000, 0, 10, 1, 3, 0.0, &a);
  EXPECT_TRUE(a.empty());
}

TEST_F(ArchiveRender, ThreadsPassesAndBudgetsGiveTheSameImage) {
  // The threads share a pass's ensembles: the thread count (capped by the ensembles resident),
  // the passes and the chunk budget (chunks per group) must not change a bit.
  const Camera camera = ObliqueView(archive_->manifest().bounds, 96, 72);
  for (double size : {1.0, 3.5}) {
    const SpbrResult ref = Reference(*archive_, camera, 10, 3, size);
    struct Case {
      int threads;
      uint64_t memory, chunk;
      int expect_threads, expect_passes;
    };
    const uint64_t frame = 12 * 96 * 72, chunk = 1024 * kChunkBytesPerPoint;
    for (const Case& c : {Case{1, 10 * frame, 1 * chunk, 1, 1}, Case{2, 20 * frame, 2 * chunk, 2, 1},
                          Case{3, 20 * frame, 8 * chunk, 3, 1}, Case{3, 6 * frame, 2 * chunk, 3, 2},
                          Case{2, 1 * frame, 8 * chunk, 1, 10}, Case{3, 2 * frame, 8 * chunk, 2, 5}}) {
      ArchiveRenderOptions o;
      o.spbr.repeat_level = 10;
      o.spbr.seed = 3;
      o.spbr.point_size = size;
      o.threads = c.threads;
      o.memory_budget = c.memory;
      o.chunk_budget = c.chunk;
      ArchiveRenderStats stats;
      const SpbrResult r = RenderArchive(o, camera, *archive_, nullptr, &stats);
      EXPECT_EQ(stats.threads, c.expect_threads) << c.threads << " threads, " << c.memory / frame << " frames";
      EXPECT_EQ(stats.passes, c.expect_passes) << c.threads << " threads, " << c.memory / frame << " frames";
      EXPECT_TRUE(r.sums == ref.sums) << "size " << size << ", " << c.threads << " threads";
      EXPECT_EQ(r.first_ensemble_grey, ref.first_ensemble_grey);
      EXPECT_EQ(r.copies, ref.copies);
    }
  }
}

// The cancel poll: a render whose poll never fires is the same image (the runs are drawn in
// pieces between polls); one that fires mid-chunk aborts with RenderCancelled, polled from within
// the chunks (every kCancelPoints points), and the archive serves the next render unchanged.
TEST_F(ArchiveRender, CancelPollsWithinChunksAndNeverChangesTheImage) {
  const Camera camera = ObliqueView(archive_->manifest().bounds, 96, 72);
  const SpbrResult ref = Reference(*archive_, camera, 1, 3, 2.0);
  ArchiveRenderOptions o;
  o.spbr.repeat_level = 1;  // one ensemble: every point of every chunk
  o.spbr.seed = 3;
  o.spbr.point_size = 2.0;
  o.threads = 2;
  std::atomic<uint64_t> polls{0};
  o.cancel = [&] {
    ++polls;
    return false;
  };
  const SpbrResult r = RenderArchive(o, camera, *archive_);
  EXPECT_TRUE(r.sums == ref.sums);
  EXPECT_EQ(r.copies, ref.copies);
  // At least one poll a piece of kCancelPoints points of each visible chunk.
  EXPECT_GE(polls.load(), archive_->manifest().chunks.size());
  // Fired at the third poll: aborted long before the last chunk (a progress callback would
  // not be called at all: the chunks all fit one group).
  polls = 0;
  o.cancel = [&] { return ++polls >= 3; };
  EXPECT_THROW(RenderArchive(o, camera, *archive_, [](uint64_t, uint64_t) { FAIL() << "reached a group's end"; }),
               RenderCancelled);
  EXPECT_LE(polls.load(), 3u + 2u);  // the other thread may poll once more each
  o.cancel = nullptr;
  EXPECT_TRUE(RenderArchive(o, camera, *archive_).sums == ref.sums);
}

TEST_F(ArchiveRender, FewerEnsemblesThanThreadsDrawMergedCopiesBitForBit) {
  // Opaque and small-L renders: the threads draw their own chunks into copies of the z-buffers,
  // merged at the end; the budget decides how many copies fit.
  const Camera camera = ObliqueView(archive_->manifest().bounds, 88, 66);
  const uint64_t frame = 12 * 88 * 66;
  struct Case {
    int L;
    uint64_t memory;
    int expect_threads, expect_replicas;
  };
  for (double size : {1.0, 2.5}) {
    for (const Case& c : {Case{1, 20 * frame, 3, 3}, Case{2, 20 * frame, 3, 3}, Case{2, 3 * frame, 2, 1},
                          Case{1, 2 * frame, 2, 2}}) {
      const SpbrResult ref = Reference(*archive_, camera, c.L, 11, size);
      ArchiveRenderOptions o;
      o.spbr.repeat_level = c.L;
      o.spbr.seed = 11;
      o.spbr.point_size = size;
      o.threads = 3;
      o.memory_budget = c.memory;
      ArchiveRenderStats stats;
      const SpbrResult r = RenderArchive(o, camera, *archive_, nullptr, &stats);
      EXPECT_EQ(stats.threads, c.expect_threads) << "L " << c.L << ", " << c.memory / frame << " frames";
      EXPECT_EQ(stats.replicas, c.expect_replicas) << "L " << c.L << ", " << c.memory / frame << " frames";
      EXPECT_EQ(stats.passes, 1);
      EXPECT_TRUE(r.sums == ref.sums) << "L " << c.L << ", size " << size;
      EXPECT_EQ(r.first_ensemble_grey, ref.first_ensemble_grey);
      EXPECT_EQ(r.copies, ref.copies);
    }
  }
}

TEST_F(ArchiveRender, EnsembleSharesAddUpToTheWhole) {
  const Camera camera = ObliqueView(archive_->manifest().bounds, 80, 60);
  ArchiveRenderOptions o;
  o.spbr.repeat_level = 9;
  const SpbrResult whole = RenderArchive(o, camera, *archive_);
  Accumulator sum(80, 60);
  uint64_t copies = 0;
  for (auto [b, e] : {std::pair{0, 4}, std::pair{4, 5}, std::pair{5, 9}}) {
    o.ensemble_begin = b, o.ensemble_end = e;
    const SpbrResult part = RenderArchive(o, camera, *archive_);
    sum.Merge(part.sums);
    copies += part.copies;
  }
  EXPECT_TRUE(sum == whole.sums);
  EXPECT_EQ(copies, whole.copies);
  EXPECT_EQ(copies, 60000u);
}

TEST_F(ArchiveRender, SkipsChunksOutsideTheViewWithoutChangingTheImage) {
  // A narrow view of one corner of the scene.
  const Box3d& b = archive_->manifest().bounds;
  Camera camera;
  camera.width = 64, camera.height = 64;
  camera.target = Eigen::Vector3d(b.min.x() + 0.15 * b.Extent().x(), b.min.y() + 0.15 * b.Extent().y(), b.min.z());
  camera.eye = camera.target + Eigen::Vector3d(0, 0, 0.3 * b.Extent().x());
  camera.up = Eigen::Vector3d::UnitY();
  camera.fov_y_deg = 30;
  ArchiveRenderOptions o;
  o.spbr.repeat_level = 6;
  ArchiveRenderStats stats;
  const SpbrResult r = RenderArchive(o, camera, *archive_, nullptr, &stats);
  EXPECT_LT(stats.chunks_visible, stats.chunks / 3);
  EXPECT_GT(stats.chunks_visible, 0u);
  EXPECT_TRUE(r.sums == Reference(*archive_, camera, 6, 1, 1.0).sums);
  uint64_t hits = 0;
  for (size_t p = 0; p < r.sums.sums.size(); p += 4) hits += r.sums.sums[p + 3];
  EXPECT_GT(hits, 0u);
}

TEST_F(ArchiveRender, ChunkBudgetBelowOneChunkIsAClearError) {
  const Camera camera = ObliqueView(archive_->manifest().bounds, 64, 48);
  ArchiveRenderOptions o;
  o.chunk_budget = 1000;
  try {
    RenderArchive(o, camera, *archive_);
    FAIL() << "rendered";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("chunk budget"), std::string::npos) << e.what();
  }
  o.chunk_budget = uint64_t{1} << 30;
  o.memory_budget = 100;
  EXPECT_THROW(RenderArchive(o, camera, *archive_), std::invalid_argument);
}

}  // namespace
}  // namespace candi::render

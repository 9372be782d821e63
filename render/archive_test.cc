#include "render/archive.h"
#include "render/archive_clip.h"

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>

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

namespace fs = std::filesystem;
using candi::testing::TempDir;

// Rounding of box.min + q * step in double: a few ulps of the largest magnitude involved.
double Slack(const ChunkQuantizer& q, int a) {
  const double mag = std::max(std::abs(q.box.min[a]), std::abs(q.box.max[a]));
  return 4 * mag * std::numeric_limits<double>::epsilon();
}

TEST(ArchiveHash, MatchesXxHash64) {
  EXPECT_EQ(ArchiveHash("", 0), 0xEF46DB3751D8E999ULL);
  const std::string text = "candi render archive chunk hashing test vector, long enough for lanes";
  EXPECT_NE(ArchiveHash(text.data(), text.size()), ArchiveHash(text.data(), text.size() - 1));
  EXPECT_NE(ArchiveHash(text.data(), text.size(), 1), ArchiveHash(text.data(), text.size(), 0));
}

TEST(ArchiveHash, BlocksHashedTogetherGiveEachBlocksOwnHash) {
  // Sizes around the 32-byte stripe and the 8- and 4-byte tails; blocks of different bytes, so
  // that lanes crossed between blocks show. On a CPU with AVX-512 this checks its path.
  Rng rng(29);
  std::vector<uint8_t> bytes(4 * 5000);
  for (uint8_t& b : bytes) b = static_cast<uint8_t>(rng.Next() >> 56);
  for (const size_t size : {size_t{0}, size_t{1}, size_t{31}, size_t{32}, size_t{33}, size_t{45},
                            size_t{64}, size_t{100}, size_t{4999}}) {
    for (int count = 0; count <= 4; ++count) {
      const uint8_t* blocks[4];
      for (int k = 0; k < 4; ++k)
        blocks[k] = bytes.data() + 5000 * k + (k == 2 ? 3 : 0);  // one unaligned
      uint64_t out[4] = {1, 1, 1, 1};
      ArchiveHashBlocks(blocks, count, size, out);
      for (int k = 0; k < 4; ++k) {
        EXPECT_EQ(out[k], k < count ? ArchiveHash(blocks[k], size) : 1u)
            << size << " bytes, " << count << " blocks";
      }
    }
  }
  // The same block given twice hashes twice alike.
  const uint8_t* twice[2] = {bytes.data(), bytes.data()};
  uint64_t out[2];
  ArchiveHashBlocks(twice, 2, 4096, out);
  EXPECT_EQ(out[0], out[1]);
  EXPECT_NE(out[0], ArchiveHash(bytes.data() + 1, 4096));
}

TEST(ChunkQuantizer, ErrorWithinDocumentedBoundOverRandomBoxes) {
  Rng rng(11);
  for (int trial = 0; trial < 400; ++trial) {
    // Extents from 1 um to 1 km, offsets up to survey scale (1e6 m), some axes flat.
    Box3d box;
    Eigen::Vector3d lo, extent;
    for (int a = 0; a < 3; ++a) {
      lo[a] = (trial % 3 == 0 ? 1e6 : 10.0) * rng.Uniform(-1, 1);
      extent[a] = rng.Uniform() < 0.15 ? 0.0 : std::pow(10.0, rng.Uniform(-6, 3));
    }
    std::vector<Eigen::Vector3d> points;
    for (int i = 0; i < 64; ++i) {
      Eigen::Vector3d p;
      for (int a = 0; a < 3; ++a) p[a] = lo[a] + extent[a] * (i < 2 ? i : rng.Uniform());
      points.push_back(p);
      box.Extend(p);
    }
    const ChunkQuantizer q = ChunkQuantizer::ForBox(box);
    ASSERT_LE(q.bits[0] + q.bits[1] + q.bits[2], kArchivePositionBits);
    for (int a = 0; a < 3; ++a) {
      if (box.max[a] > box.min[a]) {
        EXPECT_GE(q.bits[a], 1);
        EXPECT_DOUBLE_EQ(q.step[a], (box.max[a] - box.min[a]) / (std::ldexp(1.0, q.bits[a]) - 1));
      } else {
        EXPECT_EQ(q.bits[a], 0);
      }
    }
    for (size_t i = 0; i < points.size(); ++i) {
      const uint32_t rgb = static_cast<uint32_t>(i * 0x10101 + trial);
      const uint64_t word = q.Encode(points[i], rgb & 0xffffff);
      EXPECT_EQ(ChunkQuantizer::Color(word), rgb & 0xffffff);
      const Eigen::Vector3d back = q.Decode(word);
      for (int a = 0; a < 3; ++a) {
        ASSERT_LE(std::abs(back[a] - points[i][a]), q.ErrorBound(a) + Slack(q, a))
            << "trial " << trial << " axis " << a << " extent " << box.Extent()[a] << " bits " << q.bits[a];
      }
    }
  }
}

TEST(ChunkQuantizer, SinglePointAndFlatChunksAreExact) {
  Box3d single;
  single.Extend(Eigen::Vector3d(1234567.125, -7654321.5, 12.25));
  const ChunkQuantizer q = ChunkQuantizer::ForBox(single);
  EXPECT_EQ(q.bits[0] + q.bits[1] + q.bits[2], 0);
  EXPECT_EQ(q.Decode(q.Encode(single.min, 0xabcdef)), single.min);
  // A flat chunk (z constant): the 40 bits go to x and y (at most 24 each), z exact.
  Box3d flat;
  flat.Extend(Eigen::Vector3d(0, 0, 5));
  flat.Extend(Eigen::Vector3d(1, 1, 5));
  const ChunkQuantizer f = ChunkQuantizer::ForBox(flat);
  EXPECT_EQ(f.bits[0], 20);
  EXPECT_EQ(f.bits[1], 20);
  EXPECT_EQ(f.bits[2], 0);
  EXPECT_EQ(f.Decode(f.Encode(Eigen::Vector3d(0.3, 0.7, 5), 0)).z(), 5.0);
}

TEST(ChunkQuantizer, RoundsToTheNearestStepAndHalfStepsToEven) {
  // x over [0, 2^24 - 1] with 24 bits: a step of exactly 1, so q must be nearbyint(x).
  Box3d box;
  box.Extend(Eigen::Vector3d(0, 0, 0));
  box.Extend(Eigen::Vector3d(16777215.0, 0, 0));
  const ChunkQuantizer q = ChunkQuantizer::ForBox(box);
  ASSERT_EQ(q.bits[0], 24);
  ASSERT_EQ(q.step[0], 1.0);
  auto encoded = [&](double x) { return static_cast<double>(q.Encode(Eigen::Vector3d(x, 0, 0), 0) >> 24); };
  EXPECT_EQ(encoded(2.5), 2.0);  // ties to even, not away from zero
  EXPECT_EQ(encoded(3.5), 4.0);
  EXPECT_EQ(encoded(0.49999999999999994), 0.0);
  EXPECT_EQ(encoded(16777214.5), 16777214.0);
  EXPECT_EQ(encoded(-0.4), 0.0);         // clamped into the box
  EXPECT_EQ(encoded(16777215.4), 16777215.0);
  Rng rng(3);
  for (int i = 0; i < 100000; ++i) {
    const double x = i % 2 ? std::floor(rng.Uniform(0, 16777215)) + 0.5 : rng.Uniform(0, 16777215);
    ASSERT_EQ(encoded(x), std::nearbyint(x)) << std::setprecision(17) << x;
  }
}

// A cloud whose colour encodes the point's index (n < 2^24), shifted to survey coordinates.
PointCloud IndexedCloud(uint64_t n, const Eigen::Vector3d& origin) {
  PointCloud c = TerracedSolid(n, 5);
  c.frame.origin = origin;
  for (uint64_t i = 0; i < n; ++i) {
    c.colors[i] = {static_cast<uint8_t>(i >> 16), static_cast<uint8_t>(i >> 8), static_cast<uint8_t>(i)};
  }
  return c;
}

PackInput CloudInput(const PointCloud& cloud) {
  return PackInputFromGenerator("cloud", cloud.size(), 5000, [&cloud](uint64_t k, uint64_t n) {
    PointCloud part;
    part.SetSchema(cloud.schema);
    part.frame = cloud.frame;
    for (uint64_t i = k * 5000; i < k * 5000 + n; ++i) part.AppendFrom(cloud, i);
    return part;
  });
}

std::string ReadBytes(const std::string& path) { return ReadFileToString(path); }

TEST(Archive, RoundTripWithinBoundInMortonChunksInMemoryAndExternalSortAgree) {
  TempDir dir;
  const PointCloud cloud = IndexedCloud(30000, Eigen::Vector3d(500000, 4200000, 150));
  PackOptions o;
  o.chunk_points = 512;
  o.file_bytes = 64 * 1024;
  const PackSummary in_memory = PackArchive(o, {CloudInput(cloud)}, dir.path() + "/a");
  EXPECT_EQ(in_memory.spilled_points, 0u);
  o.memory_points = 2048;  // forces the bucketing on disk, nested
  const PackSummary external = PackArchive(o, {CloudInput(cloud)}, dir.path() + "/b");
  EXPECT_GE(external.spilled_points, 30000u);
  EXPECT_EQ(in_memory.points, 30000u);
  EXPECT_GT(in_memory.files, 1u);
  // The same points whichever way they were sorted (chunk cuts may differ: the external sort
  // never cuts across its cells, and each chunk is shuffled on its own).
  const PointCloud from_memory = Archive(dir.path() + "/a").ReadAll();
  const PointCloud from_disk = Archive(dir.path() + "/b").ReadAll();
  ASSERT_EQ(from_memory.size(), from_disk.size());
  auto indices = [](const PointCloud& c) {
    std::vector<uint32_t> v;
    for (const Rgb8& rgb : c.colors) v.push_back(uint32_t{rgb.r} << 16 | uint32_t{rgb.g} << 8 | rgb.b);
    std::sort(v.begin(), v.end());
    return v;
  };
  EXPECT_EQ(indices(from_memory), indices(from_disk));
  // Packing is deterministic: the same inputs and options give the same bytes.
  PackArchive(o, {CloudInput(cloud)}, dir.path() + "/c");
  EXPECT_EQ(ReadBytes(dir.path() + "/b/manifest.json"), ReadBytes(dir.path() + "/c/manifest.json"));
  EXPECT_EQ(ReadBytes(dir.path() + "/b/data-00001.bin"), ReadBytes(dir.path() + "/c/data-00001.bin"));
  fs::remove_all(dir.path() + "/c");
  // Nothing left behind but the two archives.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 2);

  const Archive archive(dir.path() + "/b");
  const ArchiveManifest& m = archive.manifest();
  EXPECT_EQ(m.frame.origin, RenderFrameFor(cloud.WorldBounds()).origin);
  std::vector<int> seen(cloud.size(), 0);
  PointCloud chunk;
  for (size_t k = 0; k < m.chunks.size(); ++k) {
    const ArchiveChunk& c = m.chunks[k];
    EXPECT_LE(c.count, o.chunk_points);
    archive.ReadChunk(k, &chunk);
    for (size_t i = 0; i < chunk.size(); ++i) {
      const Rgb8 rgb = chunk.colors[i];
      const uint64_t original = uint64_t{rgb.r} << 16 | uint64_t{rgb.g} << 8 | rgb.b;
      ASSERT_LT(original, cloud.size());
      ++seen[original];
      const Eigen::Vector3d truth = cloud.positions[original] + cloud.frame.origin - m.frame.origin;
      for (int a = 0; a < 3; ++a) {
        ASSERT_LE(std::abs(chunk.positions[i][a] - truth[a]), c.quantizer.ErrorBound(a) + Slack(c.quantizer, a));
        ASSERT_GE(chunk.positions[i][a], c.quantizer.box.min[a]);
        ASSERT_LE(chunk.positions[i][a], c.quantizer.box.max[a] + Slack(c.quantizer, a));
      }
    }
  }
  for (int s : seen) ASSERT_EQ(s, 1);
  // Chunks are compact: their boxes' total volume is below the whole box's.
  double volume = 0;
  for (const ArchiveChunk& c : m.chunks) {
    const Eigen::Vector3d e = c.quantizer.box.Extent();
    volume += e.x() * e.y() * e.z();
  }
  const Eigen::Vector3d all = m.bounds.Extent();
  EXPECT_LT(volume, 0.5 * all.x() * all.y() * all.z());  // ~60 times it in input order
  // The manifest records the source.
  ASSERT_EQ(m.sources.size(), 1u);
  EXPECT_EQ(m.sources[0].points, 30000u);
}

// True when a precedes b in Morton (Z) order of the 21-bit grid cells ia, ib: the axis whose
// coordinates differ in the highest bit decides (Chan's comparison; independent of the packer's
// bit spreading). z is the most significant axis of a 3-bit group, as in the packer's codes.
bool MortonLess(const std::array<uint32_t, 3>& a, const std::array<uint32_t, 3>& b) {
  int axis = 2;
  uint32_t top = a[2] ^ b[2];
  for (int k : {1, 0}) {
    const uint32_t d = a[k] ^ b[k];
    if (top < d && top < (top ^ d)) axis = k, top = d;  // d's highest bit is above top's
  }
  return a[axis] < b[axis];
}

TEST(Archive, PointsAreInMortonOrderForAnyThreadCount) {
  TempDir dir;
  const PointCloud cloud = IndexedCloud(20000, Eigen::Vector3d(600000, 5100000, 90));
  PackOptions o;
  o.chunk_points = 256;
  for (int threads : {1, 2}) {
    o.threads = threads;
    PackArchive(o, {CloudInput(cloud)}, dir.path() + "/t" + std::to_string(threads));
  }
  EXPECT_EQ(ReadBytes(dir.path() + "/t1/data-00000.bin"), ReadBytes(dir.path() + "/t2/data-00000.bin"));
  // The chunks come in Morton order of their points' original positions on the packer's grid
  // (21 bits per axis over the bounds): every point of a chunk is at or after every point of the
  // chunk before. Within a chunk the points are shuffled (not in Morton order).
  const Archive archive(dir.path() + "/t2");
  const ArchiveManifest& m = archive.manifest();
  const Box3d& box = m.bounds;
  auto cell = [&](uint64_t i) {
    const Eigen::Vector3d p = cloud.positions[i] + (cloud.frame.origin - m.frame.origin);
    std::array<uint32_t, 3> q;
    for (int a = 0; a < 3; ++a) {
      const double scale = std::ldexp(1.0, 21) / (box.max[a] - box.min[a]);
      q[a] = static_cast<uint32_t>(std::clamp((p[a] - box.min[a]) * scale, 0.0, std::ldexp(1.0, 21) - 1));
    }
    return q;
  };
  auto index = [&](const Rgb8& c) { return uint64_t{c.r} << 16 | uint64_t{c.g} << 8 | c.b; };
  std::array<uint32_t, 3> previous_max{};
  size_t inversions = 0, pairs = 0;
  PointCloud chunk;
  for (size_t k = 0; k < m.chunks.size(); ++k) {
    archive.ReadChunk(k, &chunk);
    std::array<uint32_t, 3> lo = cell(index(chunk.colors[0])), hi = lo;
    for (size_t i = 0; i < chunk.size(); ++i) {
      const auto c = cell(index(chunk.colors[i]));
      if (MortonLess(c, lo)) lo = c;
      if (MortonLess(hi, c)) hi = c;
      if (i > 0) {
        ++pairs;
        inversions += MortonLess(c, cell(index(chunk.colors[i - 1])));
      }
    }
    if (k > 0) {
      ASSERT_FALSE(MortonLess(lo, previous_max)) << "chunk " << k << " before the chunk ahead of it";
    }
    previous_max = hi;
  }
  EXPECT_GT(inversions, pairs / 4) << "the points of a chunk are not shuffled";
}

TEST(Archive, FloatInputsSortAsCompactRecordsIntoTheSameArchive) {
  TempDir dir;
  PointCloud cloud = IndexedCloud(30000, Eigen::Vector3d(500000, 4200000, 150));
  for (Eigen::Vector3d& p : cloud.positions) p = p.cast<float>().cast<double>();  // floats, as from PLY
  PackOptions o;
  o.chunk_points = 512;
  o.file_bytes = 64 * 1024;
  for (uint64_t memory : {uint64_t{1} << 20, uint64_t{2048}}) {  // in memory, then nested cell files
    o.memory_points = memory;
    const std::string tag = std::to_string(memory);
    o.wide_records = false;
    const PackSummary compact = PackArchive(o, {CloudInput(cloud)}, dir.path() + "/c" + tag);
    o.wide_records = true;
    const PackSummary wide = PackArchive(o, {CloudInput(cloud)}, dir.path() + "/w" + tag);
    EXPECT_EQ(compact.record_bytes, 16u);
    EXPECT_EQ(wide.record_bytes, 28u);
    EXPECT_EQ(compact.spilled_points, wide.spilled_points);
    ASSERT_GT(compact.files, 1u);
    for (uint64_t f = 0; f < compact.files; ++f) {
      char name[32];
      std::snprintf(name, sizeof(name), "/data-%05llu.bin", static_cast<unsigned long long>(f));
      ASSERT_TRUE(ReadBytes(dir.path() + "/c" + tag + name) == ReadBytes(dir.path() + "/w" + tag + name))
          << tag << name;
    }
    EXPECT_TRUE(ReadBytes(dir.path() + "/c" + tag + "/manifest.json") ==
                ReadBytes(dir.path() + "/w" + tag + "/manifest.json")) << tag;
  }
  o = PackOptions();
  // One coordinate that is not a float, or inputs in different frames: 28-byte records.
  PointCloud odd = cloud;
  odd.positions[777].x() += 1e-9;
  EXPECT_EQ(PackArchive(o, {CloudInput(odd)}, dir.path() + "/odd").record_bytes, 28u);
  PointCloud moved = cloud;
  moved.frame.origin.x() += 1;
  EXPECT_EQ(PackArchive(o, {CloudInput(cloud), CloudInput(moved)}, dir.path() + "/two").record_bytes, 28u);
  EXPECT_EQ(PackArchive(o, {CloudInput(cloud), CloudInput(cloud)}, dir.path() + "/same").record_bytes, 16u);
  // An input whose points are floats on the first read but not on the second is refused.
  int reads = 0;
  PackInput changing = PackInputFromGenerator("changing", 1000, 1000, [&](uint64_t, uint64_t n) {
    PointCloud part = TerracedSolid(n, 3);
    const bool second = reads++ > 0;
    for (Eigen::Vector3d& p : part.positions) p = p.cast<float>().cast<double>();
    if (second) part.positions[500].z() += 1e-9;
    return part;
  });
  try {
    PackArchive(o, {changing}, dir.path() + "/changed");
    FAIL() << "a changed input accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("point 500: changed between the two reads"), std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(fs::exists(dir.path() + "/changed"));
}

TEST(Archive, PackOptionsOutOfRangeAreRefused) {
  PackOptions o;
  o.Check();
  o.memory_points = uint64_t{1} << 32;  // a cell's points are indexed by 32 bits
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = PackOptions();
  o.memory_points = o.chunk_points - 1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = PackOptions();
  o.chunk_points = 32;
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

TEST(Archive, PacksPlyFilesRecordingTheirHashes) {
  TempDir dir;
  PointCloud a = TerracedSolid(3000, 1), b = TerracedSolid(2000, 2);
  io::WritePointCloud(dir.path() + "/a.ply", a);
  io::WritePointCloud(dir.path() + "/b.ply", b);
  PackOptions o;
  o.chunk_points = 256;
  PackArchive(o, {PackInputFromFile(dir.path() + "/a.ply"), PackInputFromFile(dir.path() + "/b.ply")},
              dir.path() + "/out");
  const Archive archive(dir.path() + "/out");
  ASSERT_EQ(archive.manifest().sources.size(), 2u);
  uint64_t bytes = 0;
  EXPECT_EQ(archive.manifest().sources[1].hash, HashFile(dir.path() + "/b.ply", &bytes));
  EXPECT_EQ(archive.manifest().sources[1].bytes, bytes);
  EXPECT_NE(archive.manifest().sources[0].hash, archive.manifest().sources[1].hash);
  EXPECT_EQ(archive.manifest().points, 5000u);
  // Packing again over an archive replaces it; over another kind of file is refused.
  PackArchive(o, {PackInputFromFile(dir.path() + "/b.ply")}, dir.path() + "/out");
  EXPECT_EQ(Archive(dir.path() + "/out").manifest().points, 2000u);
  EXPECT_THROW(PackArchive(o, {PackInputFromFile(dir.path() + "/b.ply")}, dir.path() + "/a.ply"), InputError);
  EXPECT_EQ(io::ReadPointCloud(dir.path() + "/a.ply").size(), 3000u);
}

TEST(Archive, RefusesEmptyAndNanInputs) {
  TempDir dir;
  PointCloud empty = TerracedSolid(0, 1);
  EXPECT_THROW(PackArchive({}, {CloudInput(empty)}, dir.path() + "/e"), InputError);
  PointCloud nan = TerracedSolid(100, 1);
  nan.positions[42].y() = std::numeric_limits<double>::quiet_NaN();
  try {
    PackArchive({}, {CloudInput(nan)}, dir.path() + "/n");
    FAIL() << "NaN accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("point 42"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir.path() + "/n"));
}

class ArchiveDamage : public ::testing::Test {
 protected:
  void SetUp() override {
    PackOptions o;
    o.chunk_points = 256;
    o.file_bytes = 16 * 1024;
    PackArchive(o, {CloudInput(cloud_)}, path_);
  }
  TempDir dir_;
  PointCloud cloud_ = TerracedSolid(8000, 3);
  std::string path_ = dir_.path() + "/arc";
};

TEST_F(ArchiveDamage, MissingDataFileNamesIt) {
  fs::remove(path_ + "/data-00001.bin");
  try {
    Archive a(path_);
    FAIL() << "opened";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("data-00001.bin"), std::string::npos) << e.what();
  }
}

TEST_F(ArchiveDamage, TruncatedDataFileNamesIt) {
  fs::resize_file(path_ + "/data-00002.bin", fs::file_size(path_ + "/data-00002.bin") - 8);
  try {
    Archive a(path_);
    FAIL() << "opened";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("data-00002.bin"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
}

TEST_F(ArchiveDamage, CorruptChunkFailsItsHash) {
  {
    std::fstream f(path_ + "/data-00000.bin", std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(3000);
    f.put('\x5a');
  }
  const Archive a(path_);
  PointCloud chunk;
  EXPECT_THROW(
      {
        for (size_t k = 0; k < a.manifest().chunks.size(); ++k) a.ReadChunk(k, &chunk);
      },
      InputError);
  ArchiveRenderOptions o;
  o.spbr.repeat_level = 4;
  Camera camera = ObliqueView(a.manifest().bounds, 64, 48);
  EXPECT_THROW(RenderArchive(o, camera, a), InputError);
}

TEST_F(ArchiveDamage, MalformedManifestNamesTheField) {
  std::string text = ReadFileToString(path_ + "/manifest.json");
  const size_t at = text.find("\"count\"");
  text.replace(at, 7, "\"cuont\"");
  WriteFileAtomic(path_ + "/manifest.json", text);
  try {
    Archive a(path_);
    FAIL() << "opened";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("count"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("chunks[0]"), std::string::npos) << e.what();
  }
}

// 8 * count wrapped 64 bits (count 2^61 + 1 looked like 8 bytes) and passed the size check once;
// the reader then allocated 2^61 points (found while writing fuzz/fuzz_archive.cc, issue 9).
TEST(ArchiveManifest, ChunkCountBeyondItsFileIsRefused) {
  ArchiveManifest m;
  m.files = {{"data-00000.bin", 8}};
  m.bounds = Box3d{Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()};
  ArchiveChunk chunk;
  chunk.count = (uint64_t{1} << 61) + 1;
  chunk.quantizer = ChunkQuantizer::ForBox(Box3d{Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()});
  m.chunks = {chunk};
  m.points = chunk.count;
  m.layers = {{"all", chunk.count}};
  try {
    ArchiveManifest::FromJson(m.ToJson(), "manifest.json");
    FAIL() << "accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("chunks[0]"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("file sizes"), std::string::npos) << e.what();
  }
  m.chunks[0].count = 1;
  m.points = 1;
  m.layers[0].points = 1;
  EXPECT_EQ(ArchiveManifest::FromJson(m.ToJson(), "manifest.json").chunks[0].count, 1u);
}

// A count of 20 digits parses as a double (beyond 64 bits); converting it to an integer was
// undefined behaviour (UBSan, found by fuzz_archive, issue 9). Fractions and negative counts too.
TEST(ArchiveManifest, IntegersThatDoNotFitAreRefused) {
  ArchiveManifest m;
  m.files = {{"data-00000.bin", 8}};
  m.bounds = Box3d{Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()};
  ArchiveChunk chunk;
  chunk.count = 1;
  chunk.quantizer = ChunkQuantizer::ForBox(Box3d{Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()});
  m.chunks = {chunk};
  m.points = 1;
  m.layers = {{"all", 1}};
  const std::string good = m.ToJson();
  ASSERT_EQ(ArchiveManifest::FromJson(good, "manifest.json").points, 1u);
  const std::string field = "\n \"points\": 1";  // the top level's (indent 1), not a layer's
  ASSERT_NE(good.find(field), std::string::npos);
  for (const std::string bad : {"23058430092136939530", "1.5", "-1", "1e300"}) {
    std::string text = good;
    text.replace(text.find(field), field.size(), "\n \"points\": " + bad);
    try {
      ArchiveManifest::FromJson(text, "manifest.json");
      ADD_FAILURE() << bad << " accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("manifest.points"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("expected an integer"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
}  // namespace candi::render

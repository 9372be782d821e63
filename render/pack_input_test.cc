// The packer's direct reading of binary PLY records (render/pack_input.h): the same archive as
// through the point readers, the manifest's hash from the same read, bad files refused.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <limits>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/rng.h"
#include "io/point_io.h"
#include "render/archive.h"
#include "render/archive_pack.h"
#include "render/pack_input.h"
#include "render/pack_records.h"
#include "render/synthetic_scene.h"
#include "tests/util/test_util.h"

namespace candi::render {
namespace {

namespace fs = std::filesystem;
using candi::testing::TempDir;

// A binary PLY of float positions (local, in the cloud's frame) via the project's writer.
void WriteFloatPly(const std::string& path, const PointCloud& cloud) {
  io::PointWriteOptions o;
  o.precision = io::PositionPrecision::kFloat32;
  io::WritePointCloud(path, cloud, o);
}

PointCloud Scene(uint64_t n, uint64_t seed, bool colors, bool normals) {
  PointCloud c = TerracedSolid(n, seed);
  c.frame.origin = Eigen::Vector3d(500000, 4200000, 150);  // survey coordinates: a shifted frame
  PointSchema s = c.schema;
  s.colors = colors;
  s.normals = normals;
  c.SetSchema(s);
  for (uint64_t i = 0; i < n; ++i) {
    if (colors) c.colors[i] = {static_cast<uint8_t>(i >> 16), static_cast<uint8_t>(i >> 8), static_cast<uint8_t>(i)};
    if (normals) c.normals[i] = Eigen::Vector3f(0, 0, 1);
  }
  return c;
}

void ExpectSameArchive(const std::string& a, const std::string& b, const std::string& what) {
  const Archive x(a), y(b);
  ASSERT_EQ(x.manifest().files.size(), y.manifest().files.size()) << what;
  for (const ArchiveFile& f : x.manifest().files) {
    EXPECT_TRUE(ReadFileToString(a + "/" + f.name) == ReadFileToString(b + "/" + f.name)) << what << " " << f.name;
  }
  EXPECT_EQ(ReadFileToString(a + "/manifest.json"), ReadFileToString(b + "/manifest.json")) << what;
}

TEST(PackRecords, VectorizedKernelsEqualTheGridsCodeAndTheQuantizersEncode) {
  // Survey-scale shift, points beyond the grid on both sides (clamped), a count that is not a
  // multiple of the 256-point blocks; floats, doubles, and LAS integers with a decimal scale and
  // with another.
  using namespace pack_internal;
  MortonGrid grid;
  grid.min = Eigen::Vector3d(-3.25, 10.5, -0.125);
  grid.scale = Eigen::Vector3d(std::ldexp(1.0, kMortonBits) / 7.5, std::ldexp(1.0, kMortonBits) / 0.01, 0.0);
  RecordFrame frame;
  frame.shift = Eigen::Vector3d(-250.0, 12.0, 0.5);
  Rng rng(3);
  const size_t n = 1000;
  std::vector<CompactPoint> compact(n);
  std::vector<WidePoint> wide(n);
  std::vector<LasPoint> las(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p(rng.Uniform(244.0, 256.0), rng.Uniform(-1.6, -1.4), rng.Uniform(-9.0, 9.0));
    const uint32_t rgb = static_cast<uint32_t>(rng.Next());  // the top byte is not a colour's
    compact[i] = {static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()), rgb};
    const Eigen::Vector3d q = compact[i].Position(frame);
    wide[i] = {q.x(), q.y(), q.z(), rgb};
    las[i] = {static_cast<int32_t>(p.x() * 1000), static_cast<int32_t>(p.y() * 1000), static_cast<int32_t>(p.z() * 1000),
              rgb};
  }
  // Each record type against Code of its Position, and how many were clamped on x.
  auto check = [&](const RecordFrame& f, const auto& points, const char* what) {
    std::vector<uint64_t> codes(n);
    MortonCodes(grid, f, points.data(), n, codes.data());
    size_t low = 0, high = 0;
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d p = points[i].Position(f);
      ASSERT_EQ(codes[i], grid.Code(p)) << what << " " << i;
      uint64_t q[3];
      grid.Quantize(p, q);
      low += q[0] == 0;
      high += q[0] == (1u << kMortonBits) - 1;
    }
    EXPECT_GT(low, 0u) << what;
    EXPECT_GT(high, 0u) << what;
    // The routing's cells: the codes' bits `levels` below a node `shift` levels above the finest.
    std::vector<uint16_t> cells(n);
    for (int levels = 1; levels <= 3; ++levels) {
      for (int shift : {0, 1, 7, kMortonBits - 3 - levels, kMortonBits - levels}) {
        MortonCells(grid, f, points.data(), n, shift, levels, cells.data());
        const uint64_t mask = (uint64_t{1} << (3 * levels)) - 1;
        for (size_t i = 0; i < n; ++i) {
          ASSERT_EQ(cells[i], (codes[i] >> (3 * shift)) & mask) << what << " levels " << levels << " shift " << shift;
        }
      }
    }
    // The block encoder against ChunkQuantizer::Encode, on a box that clamps points on both
    // sides of x and y, and on one flat on z (no bits for it).
    Box3d box;
    for (size_t i = 0; i < n; ++i) box.Extend(points[i].Position(f));
    const Eigen::Vector3d mid = box.Center(), half = 0.3 * box.Extent();
    for (const bool flat : {false, true}) {
      Box3d inner;
      inner.Extend(Eigen::Vector3d(mid.x() - half.x(), mid.y() - half.y(), flat ? mid.z() : box.min.z()));
      inner.Extend(Eigen::Vector3d(mid.x() + half.x(), mid.y() + half.y(), flat ? mid.z() : box.max.z()));
      const ChunkQuantizer q = ChunkQuantizer::ForBox(inner);
      ASSERT_EQ(q.bits[2] == 0, flat);
      std::vector<uint64_t> words(n);
      Encode(q, f, points.data(), n, words.data());
      for (size_t i = 0; i < n; ++i) {
        ASSERT_EQ(words[i], q.Encode(points[i].Position(f), points[i].rgb)) << what << " point " << i;
      }
    }
  };
  check(frame, compact, "floats");
  check(RecordFrame(), wide, "doubles");
  RecordFrame decimal = frame, other = frame;
  decimal.las = io::LasPositionDecoder(Eigen::Vector3d::Constant(0.001), Eigen::Vector3d(2.0, -1.0, 0.0));
  other.las = io::LasPositionDecoder(Eigen::Vector3d::Constant(0.003), Eigen::Vector3d(-488.0, 0.3, 0.0));
  ASSERT_TRUE(decimal.las.decimal);
  ASSERT_FALSE(other.las.decimal);
  check(decimal, las, "LAS, decimal scale");
  check(other, las, "LAS, other scale");
}

TEST(PackDirect, PlyRecordsGiveTheSameArchiveAsThePointReaders) {
  TempDir dir;
  // Two files in one shifted frame: colours, and no colours with normals (another record size).
  WriteFloatPly(dir.File("a.ply"), Scene(20000, 1, true, false));
  WriteFloatPly(dir.File("b.ply"), Scene(9000, 2, false, true));
  ASSERT_TRUE(io::OpenPointReader(dir.File("a.ply"))->record_layout().has_value());
  ASSERT_TRUE(io::OpenPointReader(dir.File("b.ply"))->record_layout().has_value());
  const std::vector<PackInput> inputs = {PackInputFromFile(dir.File("a.ply")), PackInputFromFile(dir.File("b.ply"))};
  PackOptions o;
  o.chunk_points = 512;
  o.file_bytes = 64 * 1024;
  for (uint64_t memory : {uint64_t{1} << 20, uint64_t{2048}}) {  // in memory, then nested cell files
    o.memory_points = memory;
    const std::string tag = std::to_string(memory);
    o.direct_reads = true;
    const PackSummary direct = PackArchive(o, inputs, dir.File("d" + tag));
    o.direct_reads = false;
    const PackSummary read = PackArchive(o, inputs, dir.File("r" + tag));
    EXPECT_EQ(direct.record_bytes, 16u);
    EXPECT_EQ(read.record_bytes, 16u);
    EXPECT_EQ(direct.points, 29000u);
    EXPECT_GT(direct.files, 1u);
    ExpectSameArchive(dir.File("d" + tag), dir.File("r" + tag), tag);
  }
  // Files in different frames: 28-byte records, still the same archive.
  PointCloud moved = Scene(5000, 3, true, false);
  moved.frame.origin.x() += 1;
  WriteFloatPly(dir.File("c.ply"), moved);
  const std::vector<PackInput> mixed = {PackInputFromFile(dir.File("a.ply")), PackInputFromFile(dir.File("c.ply"))};
  o.direct_reads = true;
  EXPECT_EQ(PackArchive(o, mixed, dir.File("dm")).record_bytes, 28u);
  o.direct_reads = false;
  PackArchive(o, mixed, dir.File("rm"));
  ExpectSameArchive(dir.File("dm"), dir.File("rm"), "mixed frames");
}

TEST(PackDirect, PlyOfDoublesIsScannedInOneReadForTheArchiveOfThePointReaders) {
  TempDir dir;
  io::PointWriteOptions doubles;
  doubles.precision = io::PositionPrecision::kFloat64;
  // Doubles a float does not hold (28-byte records), and doubles that are all floats (16-byte
  // records): the bounds, the hash and the archive of the readers' pass.
  PointCloud wide = Scene(20000, 21, true, false), exact = Scene(9000, 22, false, false);
  for (Eigen::Vector3d& p : exact.positions) p = p.cast<float>().cast<double>();
  io::WritePointCloud(dir.File("wide.ply"), wide, doubles);
  io::WritePointCloud(dir.File("exact.ply"), exact, doubles);
  for (const std::string name : {"wide.ply", "exact.ply"}) {
    ASSERT_EQ(io::OpenPointReader(dir.File(name))->record_layout()->coordinates,
              io::PointRecordLayout::Coordinates::kFloat64) << name;
  }
  PackOptions o;
  o.chunk_points = 512;
  o.file_bytes = 64 * 1024;
  for (const std::string name : {"wide.ply", "exact.ply"}) {
    for (uint64_t memory : {uint64_t{1} << 20, uint64_t{2048}}) {
      o.memory_points = memory;
      const std::string tag = name + std::to_string(memory);
      o.direct_reads = true;
      const PackSummary direct = PackArchive(o, {PackInputFromFile(dir.File(name))}, dir.File("d" + tag));
      o.direct_reads = false;
      const PackSummary read = PackArchive(o, {PackInputFromFile(dir.File(name))}, dir.File("r" + tag));
      const size_t bytes = name == std::string("wide.ply") ? 28u : 16u;
      EXPECT_EQ(direct.record_bytes, bytes) << tag;
      EXPECT_EQ(read.record_bytes, bytes) << tag;
      EXPECT_EQ(direct.hash_seconds, 0.0) << tag << ": hashed in pass 1's read, not on another thread";
      ExpectSameArchive(dir.File("d" + tag), dir.File("r" + tag), tag);
    }
  }
  // A NaN, then an infinity: refused naming the first vertex, as the PLY reader does.
  wide.positions[15000].x() = std::numeric_limits<double>::quiet_NaN();
  wide.positions[17000].z() = -std::numeric_limits<double>::infinity();
  io::WritePointCloud(dir.File("nan.ply"), wide, doubles);
  try {
    PackArchive({}, {PackInputFromFile(dir.File("nan.ply"))}, dir.File("out"));
    ADD_FAILURE() << "nan.ply accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 15000: coordinate is NaN or infinite"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(dir.File("out")));
}

TEST(PackDirect, LasRecordsGiveTheSameArchiveAsThePointReaders) {
  TempDir dir;
  // Survey coordinates in LAS (world, int32 with scale and offset): a decimal scale, then one
  // that is not (positions X * scale + offset).
  for (const double scale : {0.001, 0.0003}) {
    const std::string tag = scale == 0.001 ? "mm" : "odd";
    io::PointWriteOptions w;
    w.las_scale = Eigen::Vector3d::Constant(scale);
    w.las_offset = Eigen::Vector3d(500000, 4200000, 100);
    io::WritePointCloud(dir.File(tag + "a.las"), Scene(20000, 7, true, false), w);
    io::WritePointCloud(dir.File(tag + "b.las"), Scene(7000, 8, true, false), w);
    {
      // 16-bit colours whose low bytes are not copies of the high ones (the writer's v * 257):
      // the colour is the high byte.
      const io::PointRecordLayout l = *io::OpenPointReader(dir.File(tag + "a.las"))->record_layout();
      ASSERT_EQ(l.color_shift, 8);
      std::string bytes = ReadFileToString(dir.File(tag + "a.las"));
      for (uint64_t i = 0; i < l.count; ++i) {
        for (int c = 0; c < 3; ++c) bytes[l.first_byte + i * l.stride + l.rgb[c]] = static_cast<char>(i * 7 + c);
      }
      WriteFileAtomic(dir.File(tag + "a.las"), bytes);
    }
    const std::vector<PackInput> inputs = {PackInputFromFile(dir.File(tag + "a.las")),
                                           PackInputFromFile(dir.File(tag + "b.las"))};
    PackOptions o;
    o.chunk_points = 512;
    o.file_bytes = 64 * 1024;
    for (uint64_t memory : {uint64_t{1} << 20, uint64_t{2048}}) {
      o.memory_points = memory;
      const std::string name = tag + std::to_string(memory);
      o.direct_reads = true;
      EXPECT_EQ(PackArchive(o, inputs, dir.File("d" + name)).record_bytes, 16u) << name;
      o.direct_reads = false;
      EXPECT_EQ(PackArchive(o, inputs, dir.File("r" + name)).record_bytes, 28u) << name;
      ExpectSameArchive(dir.File("d" + name), dir.File("r" + name), name);
    }
  }
  // LAS files of different scales: 28-byte records.
  EXPECT_EQ(PackArchive({}, {PackInputFromFile(dir.File("mma.las")), PackInputFromFile(dir.File("odda.las"))},
                        dir.File("mixed")).record_bytes, 28u);
}

TEST(PackDirect, HashOfAFileOfSeveralBlocksIsHashFiles) {
  // 4.6 million 15-byte records: 69 MB, two hash blocks of 64 MiB with a record across the cut.
  TempDir dir;
  PointCloud cloud = Scene(4600000, 4, true, false);
  WriteFloatPly(dir.File("big.ply"), cloud);
  // The record across the cut holds the largest x, so the bounds miss it if that record is lost.
  const uint64_t first = io::OpenPointReader(dir.File("big.ply"))->record_layout()->first_byte;
  const size_t across = static_cast<size_t>(((uint64_t{64} << 20) - first) / 15);
  ASSERT_GT(first + 15 * (across + 1), uint64_t{64} << 20);
  cloud.positions[across].x() = cloud.LocalBounds().max.x() + 1.5;
  WriteFloatPly(dir.File("big.ply"), cloud);
  PackOptions o;
  o.memory_points = uint64_t{1} << 23;
  PackArchive(o, {PackInputFromFile(dir.File("big.ply"))}, dir.File("out"));
  const Archive archive(dir.File("out"));
  uint64_t bytes = 0;
  const uint64_t hash = HashFile(dir.File("big.ply"), &bytes);
  ASSERT_GT(bytes, uint64_t{64} << 20);
  EXPECT_EQ(archive.manifest().sources.at(0).hash, hash);
  EXPECT_EQ(archive.manifest().sources.at(0).bytes, bytes);
  EXPECT_EQ(archive.manifest().points, 4600000u);
  const Box3d world = io::ReadPointCloud(dir.File("big.ply")).WorldBounds();
  EXPECT_EQ(archive.manifest().bounds.max, world.Translated(-archive.manifest().frame.origin).max);
  EXPECT_EQ(archive.manifest().bounds.min, world.Translated(-archive.manifest().frame.origin).min);
}

TEST(PackDirect, HashFileIsTheHashOfItsBlocksHashes) {
  // Six whole 64 MiB blocks (hashed four together, then two) and a tail, against the
  // definition. The file is sparse except for a distinct page in every block, so it costs no
  // disk and crossed blocks show.
  TempDir dir;
  const std::string path = dir.File("sparse.bin");
  constexpr uint64_t kBlock = pack_internal::kHashBlock;
  const uint64_t size = 6 * kBlock + 5000;
  const int fd = open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  ASSERT_GE(fd, 0);
  for (uint64_t b = 0; b <= 6; ++b) {
    std::vector<uint8_t> page(4096);
    for (size_t i = 0; i < page.size(); ++i) page[i] = static_cast<uint8_t>(31 * b + i);
    ASSERT_EQ(pwrite(fd, page.data(), page.size(), static_cast<off_t>(b * kBlock + 1000 * b)),
              4096);
  }
  ASSERT_EQ(ftruncate(fd, static_cast<off_t>(size)), 0);
  close(fd);
  const std::string bytes = candi::testing::ReadBytes(path);
  ASSERT_EQ(bytes.size(), size);
  std::vector<uint64_t> blocks;
  for (uint64_t at = 0; at < size; at += kBlock) {
    blocks.push_back(
        ArchiveHash(bytes.data() + at, static_cast<size_t>(std::min(kBlock, size - at))));
  }
  uint64_t hashed = 0;
  EXPECT_EQ(HashFile(path, &hashed), ArchiveHash(blocks.data(), 8 * blocks.size(), size));
  EXPECT_EQ(hashed, size);
}

TEST(PackDirect, NanAndTruncatedFilesAreRefusedNamingTheVertex) {
  TempDir dir;
  PointCloud cloud = Scene(40000, 5, true, false);
  cloud.positions[33000].y() = std::numeric_limits<double>::quiet_NaN();
  cloud.positions[37000].z() = std::numeric_limits<double>::infinity();
  WriteFloatPly(dir.File("nan.ply"), cloud);
  auto refused = [&](const std::string& file, const std::string& message) {
    try {
      PackArchive({}, {PackInputFromFile(dir.File(file))}, dir.File("out"));
      ADD_FAILURE() << file << " accepted";
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(file), std::string::npos) << what;
      EXPECT_NE(what.find(message), std::string::npos) << what;
    }
    EXPECT_FALSE(fs::exists(dir.File("out"))) << file;
  };
  refused("nan.ply", "vertex 33000: coordinate is NaN or infinite");
  // Cut inside vertex 30000 (15 bytes a vertex after the header): the reader's header check
  // refuses it before any record is read.
  WriteFloatPly(dir.File("cut.ply"), Scene(40000, 6, true, false));
  const uint64_t size = fs::file_size(dir.File("cut.ply"));
  fs::resize_file(dir.File("cut.ply"), size - 10000 * 15 + 7);
  refused("cut.ply", "header promises 40000 vertex records");
}

}  // namespace
}  // namespace candi::render

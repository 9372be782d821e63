// LAZ decoding: the arithmetic coder's edge behaviour, the laszip VLR, and LAZ files written by
// LASzip and laz-perf decoded to exactly the records of their uncompressed counterparts.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <functional>

#include "core/binary_file.h"
#include "core/check.h"
#include "io/las/las_header.h"
#include "io/las/las_io.h"
#include "io/laz/laz_arith.h"
#include "io/laz/laz_chunks.h"
#include "io/laz/laz_format.h"
#include "io/point_io.h"
#include "tests/util/input_error.h"
#include "tests/util/las_bytes.h"
#include "tests/util/laz_records.h"
#include "tests/util/read_in_chunks.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using ::candi::testing::GetLE;
using ::candi::testing::InputErrorMessage;
using ::candi::testing::LasPointRecords;
using ::candi::testing::LaszipVlrOf;
using ::candi::testing::LazRecords;
using ::candi::testing::PutLE;
using ::candi::testing::ReadBytes;
using ::candi::testing::ReadInChunks;
using ::candi::testing::SourceDir;
using ::candi::testing::TempDir;
using ::candi::testing::WriteBytes;

std::string DataPath(const std::string& name) { return SourceDir() + "/tests/data/laz/" + name; }


PointCloud ReadWith(const std::string& path, size_t read_size) {
  return ReadInChunks(*OpenPointReader(path), read_size);
}

void ExpectSameClouds(const PointCloud& a, const PointCloud& b) {
  ASSERT_EQ(a.size(), b.size());
  ASSERT_TRUE(a.schema == b.schema);
  for (size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a.positions[i], b.positions[i]) << "point " << i;
    if (a.schema.colors) {
      ASSERT_EQ(a.colors[i].r, b.colors[i].r) << "point " << i;
      ASSERT_EQ(a.colors[i].g, b.colors[i].g) << "point " << i;
      ASSERT_EQ(a.colors[i].b, b.colors[i].b) << "point " << i;
    }
  }
  for (const ScalarFieldSpec& spec : a.schema.scalars) {
    const ScalarField* fa = a.FindScalar(spec.name);
    const ScalarField* fb = b.FindScalar(spec.name);
    ASSERT_TRUE(fa && fb) << spec.name;
    for (size_t i = 0; i < a.size(); ++i) {
      ASSERT_EQ(fa->Get(i), fb->Get(i)) << spec.name << " of point " << i;
    }
  }
}

// The LAZ file decodes to the LAS file's records, and reads to the same cloud and metadata.
void ExpectLazMatchesLas(const std::string& laz, const std::string& las) {
  const std::string expected = LasPointRecords(ReadBytes(las));
  const std::string decoded = LazRecords(laz);
  ASSERT_EQ(decoded.size(), expected.size());
  EXPECT_TRUE(decoded == expected) << "decoded records differ";
  const PointCloud a = ReadPointCloud(laz);
  const PointCloud b = ReadPointCloud(las);
  ExpectSameClouds(a, b);
  EXPECT_EQ(a.meta.las.point_format, b.meta.las.point_format);
  EXPECT_EQ(a.meta.las.color_16bit, b.meta.las.color_16bit);
  for (const LasVlr& vlr : a.meta.las.vlrs) EXPECT_NE(vlr.user_id, "laszip encoded");
  EXPECT_EQ(OpenPointReader(laz)->info().description.rfind("LAZ: ", 0), 0u);
}

// Opens and reads the whole file; "" when it reads, else the InputError (any other exception
// fails the test).
std::string ReadError(const std::string& path) {
  return InputErrorMessage([&] { ReadWith(path, 1 << 16); });
}

// The byte offset of the laszip VLR's payload.
size_t LaszipPayload(const std::string& file) {
  const size_t user_id = file.find("laszip encoded");
  EXPECT_NE(user_id, std::string::npos);
  return user_id - 2 + 54;
}

// ---- The arithmetic decoder ----

TEST(LazArith, EmptyInputOverrunsAndReadsNothing) {
  laz::ArithmeticDecoder decoder;
  const uint8_t byte = 0x5A;
  decoder.Init(&byte, &byte);
  EXPECT_TRUE(decoder.overrun());
  EXPECT_EQ(decoder.consumed(), 0u);
  laz::SymbolModel model(256);
  laz::BitModel bit;
  for (int i = 0; i < 1000; ++i) {
    EXPECT_LT(decoder.DecodeSymbol(&model), 256u);
    EXPECT_LE(decoder.DecodeBit(&bit), 1u);
  }
  EXPECT_EQ(decoder.consumed(), 0u);
}

TEST(LazArith, ShortInputOverrunsWithinBounds) {
  std::vector<uint8_t> bytes = {0xFF, 0xFF, 0xFF, 0xFF, 0xFF, 0x12};  // worst case: value = max
  laz::ArithmeticDecoder decoder;
  decoder.Init(bytes.data(), bytes.data() + bytes.size());
  EXPECT_FALSE(decoder.overrun());
  EXPECT_EQ(decoder.consumed(), 4u);
  laz::SymbolModel small(5), large(2048);
  laz::IntegerCoder ic(32, 3);
  ic.Init();
  for (int i = 0; i < 200; ++i) {
    EXPECT_LT(decoder.DecodeSymbol(&small), 5u);
    EXPECT_LT(decoder.DecodeSymbol(&large), 2048u);
    ic.Decompress(&decoder, i, i % 3);
    decoder.ReadBits(1 + i % 32);
    decoder.ReadInt64();
  }
  EXPECT_TRUE(decoder.overrun());
  EXPECT_EQ(decoder.consumed(), bytes.size());
}

TEST(LazArith, RawReadsOfAKnownStream) {
  // With length 2^32-1 the first 16-bit raw read is value / 65535: 0x0001_0001 gives 1.
  const uint8_t bytes[] = {0x00, 0x01, 0x00, 0x01, 0, 0, 0, 0};
  laz::ArithmeticDecoder decoder;
  decoder.Init(bytes, bytes + sizeof(bytes));
  EXPECT_EQ(decoder.ReadShort(), 1u);
  EXPECT_FALSE(decoder.overrun());
}

TEST(LazArith, SymbolModelChecksItsSize) {
  EXPECT_THROW(laz::SymbolModel(1), InternalError);
  EXPECT_THROW(laz::SymbolModel(2049), InternalError);
  EXPECT_EQ(laz::SymbolModel(2).symbols(), 2u);
  EXPECT_EQ(laz::SymbolModel(2048).symbols(), 2048u);
}

// ---- The laszip VLR ----

std::string VlrPayload(uint16_t compressor, std::vector<laz::Item> items, uint16_t coder = 0) {
  std::string p(34 + 6 * items.size(), '\0');
  PutLE<uint16_t>(&p, 0, compressor);
  PutLE<uint16_t>(&p, 2, coder);
  p[4] = 2, p[5] = 2;
  PutLE<uint32_t>(&p, 12, 50000);
  PutLE<int64_t>(&p, 16, -1);
  PutLE<int64_t>(&p, 24, -1);
  PutLE<uint16_t>(&p, 32, static_cast<uint16_t>(items.size()));
  for (size_t i = 0; i < items.size(); ++i) {
    PutLE<uint16_t>(&p, 34 + 6 * i, items[i].type);
    PutLE<uint16_t>(&p, 36 + 6 * i, items[i].size);
    PutLE<uint16_t>(&p, 38 + 6 * i, items[i].version);
  }
  return p;
}

std::string SupportError(const std::string& payload, int format, int length) {
  try {
    laz::CheckSupported(laz::ParseVlr(payload), format, length);
  } catch (const laz::LazError& e) {
    return e.what();
  }
  return "";
}

TEST(LazFormat, ParsesAndDescribesTheVlr) {
  const laz::Vlr vlr =
      laz::ParseVlr(VlrPayload(2, {{laz::kPoint10, 20, 2}, {laz::kGpsTime11, 8, 2},
                                   {laz::kRgb12, 6, 2}, {laz::kByte, 3, 2}}));
  EXPECT_EQ(vlr.compressor, 2);
  EXPECT_EQ(vlr.chunk_size, 50000u);
  EXPECT_EQ(vlr.record_length(), 37);
  EXPECT_EQ(laz::Describe(vlr),
            "LASzip 2.2r0, pointwise chunked compressor (v2), 50000-point chunks, items POINT10 "
            "v2, GPSTIME11 v2, RGB12 v2, BYTE v2 (3 bytes)");
  EXPECT_EQ(SupportError(VlrPayload(2, vlr.items), 3, 37), "");
  EXPECT_EQ(SupportError(VlrPayload(3, {{laz::kPoint14, 30, 3}, {laz::kRgb14, 6, 3}}), 7, 36), "");
  EXPECT_EQ(laz::ItemTypeName(42), "item type 42");
}

TEST(LazFormat, RefusesWhatItDoesNotDecode) {
  const std::vector<laz::Item> p10 = {{laz::kPoint10, 20, 2}};
  EXPECT_THROW(laz::ParseVlr(std::string(20, '\0')), laz::LazError);
  EXPECT_THROW(laz::ParseVlr(VlrPayload(2, p10).substr(0, 38)), laz::LazError);
  auto has = [](const std::string& error, const std::string& part) {
    return error.find(part) != std::string::npos;
  };
  EXPECT_TRUE(has(SupportError(VlrPayload(1, p10), 0, 20), "compressor 1")) << "compressor 1";
  EXPECT_TRUE(has(SupportError(VlrPayload(2, p10, 1), 0, 20), "coder 1"));
  EXPECT_TRUE(has(SupportError(VlrPayload(2, {{laz::kPoint10, 20, 1}}), 0, 20),
                  "item POINT10 version 1 (LASzip 1.x) is not supported; candi decodes version 2"));
  EXPECT_TRUE(has(SupportError(VlrPayload(2, {{laz::kPoint10, 20, 2}, {42, 4, 2}}), 0, 24),
                  "item type 42"));
  EXPECT_TRUE(has(SupportError(VlrPayload(2, {{laz::kPoint10, 20, 2}, {laz::kWavepacket13, 29, 2}}),
                               0, 49),
                  "WAVEPACKET13"));
  EXPECT_TRUE(has(SupportError(VlrPayload(2, p10), 1, 28), "do not match point format 1"));
  EXPECT_TRUE(has(SupportError(VlrPayload(2, p10), 0, 24), "record length is 24"));
  EXPECT_TRUE(has(SupportError(VlrPayload(2, {{laz::kPoint10, 22, 2}}), 0, 22), "size 22"));
  EXPECT_TRUE(has(SupportError(VlrPayload(2, {{laz::kPoint14, 30, 3}}), 6, 30), "belong"));
}

// ---- Files written by LASzip and laz-perf ----

TEST(LazRead, DecodesToTheRecordsOfTheLasFile) {
  ExpectLazMatchesLas(DataPath("1815.laz"), DataPath("1815.las"));
  ExpectLazMatchesLas(DataPath("extrabytes.laz"), DataPath("extrabytes.las"));
}

TEST(LazRead, SharedDataDecodesToTheRecordsOfTheLasFile) {
  CANDI_REQUIRE_SHARED_DATA(simple, "las/simple.las");
  ExpectLazMatchesLas(DataPath("simple.laz"), simple);
  CANDI_REQUIRE_SHARED_DATA(autzen_laz, "las/autzen_trim.laz");
  CANDI_REQUIRE_SHARED_DATA(autzen_las, "las/autzen_trim.las");
  ExpectLazMatchesLas(autzen_laz, autzen_las);
}

TEST(LazRead, NoPointsAndLas14) {
  auto empty = OpenPointReader(DataPath("no-points-1.3.laz"));
  EXPECT_EQ(empty->info().count, 0u);
  PointCloud chunk;
  EXPECT_EQ(empty->Read(100, &chunk), 0u);
  auto reader = OpenPointReader(DataPath("point-time-1.4.las.laz"));
  EXPECT_GT(reader->info().count, 0u);
  const PointCloud cloud = ReadWith(DataPath("point-time-1.4.las.laz"), 1 << 20);
  EXPECT_EQ(cloud.size(), reader->info().count);
  ASSERT_NE(cloud.FindScalar(las_field::kGpsTime), nullptr);
}

TEST(LazRead, ReadSizesAndThreadCountsAgree) {
  const std::string path = DataPath("1815.laz");
  const PointCloud reference = ReadWith(path, 1 << 20);
  ExpectSameClouds(ReadWith(path, 1), reference);
  ExpectSameClouds(ReadWith(path, 1000), reference);
  ExpectSameClouds(ReadWith(path, 777), reference);
  tbb::task_arena one(1);
  one.execute([&] { ExpectSameClouds(ReadWith(path, 1000), reference); });
  tbb::task_arena three(3);
  three.execute([&] { ExpectSameClouds(ReadWith(path, 1 << 20), reference); });
}

TEST(LazRead, SharedDataReadSizesAndThreadCountsAgree) {
  CANDI_REQUIRE_SHARED_DATA(path, "las/autzen_trim.laz");
  const PointCloud reference = ReadWith(path, 1 << 20);
  ExpectSameClouds(ReadWith(path, 1000), reference);
  ExpectSameClouds(ReadWith(path, 65537), reference);
  tbb::task_arena one(1);
  one.execute([&] { ExpectSameClouds(ReadWith(path, 1 << 20), reference); });
}

TEST(LazRead, ConvertedToLasKeepsNoLaszipVlr) {
  TempDir dir;
  const PointCloud cloud = ReadPointCloud(DataPath("extrabytes.laz"));
  WritePointCloud(dir.File("out.las"), cloud);
  auto reader = OpenPointReader(dir.File("out.las"));
  EXPECT_EQ(reader->info().meta.las.point_format, 3);
  for (const LasVlr& vlr : reader->info().meta.las.vlrs) EXPECT_NE(vlr.user_id, "laszip encoded");
  ExpectSameClouds(ReadPointCloud(dir.File("out.las")), cloud);
}

// ---- Bad input: an InputError naming the path, never a crash, a hang or a huge allocation ----

TEST(LazRead, TruncatedFilesAreInputErrors) {
  const std::string bytes = ReadBytes(DataPath("1815.laz"));
  TempDir dir;
  const std::string path = dir.File("cut.laz");
  for (size_t cut = 0; cut < bytes.size(); cut += 1 + bytes.size() / 97) {
    WriteBytes(path, bytes.substr(0, cut));
    const std::string error = ReadError(path);
    EXPECT_NE(error.find(path), std::string::npos) << "cut at " << cut << ": " << error;
  }
}

TEST(LazRead, BitFlipsAreInputErrorsOrDecode) {
  const std::string bytes = ReadBytes(DataPath("1815.laz"));
  const size_t point_data = GetLE<uint32_t>(bytes, 96);
  const size_t table = static_cast<size_t>(GetLE<int64_t>(bytes, point_data));
  TempDir dir;
  const std::string path = dir.File("flip.laz");
  int errors = 0;
  // Chunk data and chunk table: corrupt arithmetic data may decode to other points; what
  // matters is that it never reads out of bounds, crashes or throws anything but InputError.
  for (size_t at = point_data; at < bytes.size(); at += 1 + (bytes.size() - point_data) / 150) {
    for (int bit : {0, 7}) {
      std::string flipped = bytes;
      flipped[at] = static_cast<char>(flipped[at] ^ (1 << bit));
      WriteBytes(path, flipped);
      const std::string error = ReadError(path);
      errors += !error.empty();
      EXPECT_TRUE(error.empty() || error.find(path) != std::string::npos) << error;
    }
  }
  for (size_t at = table; at < bytes.size(); ++at) {
    std::string flipped = bytes;
    flipped[at] = static_cast<char>(~flipped[at]);
    WriteBytes(path, flipped);
    const std::string error = ReadError(path);
    errors += !error.empty();
    EXPECT_TRUE(error.empty() || error.find(path) != std::string::npos) << error;
  }
  EXPECT_GT(errors, 0);
}

TEST(LazRead, AbsurdCountsAreInputErrors) {
  const std::string bytes = ReadBytes(DataPath("1815.laz"));
  const size_t point_data = GetLE<uint32_t>(bytes, 96);
  const size_t table = static_cast<size_t>(GetLE<int64_t>(bytes, point_data));
  TempDir dir;
  const std::string path = dir.File("bad.laz");
  auto error_after = [&](const std::function<void(std::string*)>& edit) {
    std::string b = bytes;
    edit(&b);
    WriteBytes(path, b);
    return ReadError(path);
  };
  auto has = [](const std::string& error, const std::string& part) {
    return error.find(part) != std::string::npos;
  };
  // Header count: 2^32 - 1 in a LAS 1.2 file.
  std::string e = error_after([](std::string* b) { PutLE<uint32_t>(b, 107, 0xFFFFFFFFu); });
  EXPECT_TRUE(has(e, path) && has(e, "chunk table")) << e;
  e = error_after([&](std::string* b) { PutLE<uint32_t>(b, table + 4, 0xFFFFFFFFu); });
  EXPECT_TRUE(has(e, "lists 4294967295 chunks")) << e;
  e = error_after([&](std::string* b) { PutLE<uint32_t>(b, table, 7); });
  EXPECT_TRUE(has(e, "version 7")) << e;
  e = error_after([&](std::string* b) { PutLE<int64_t>(b, point_data, int64_t{1} << 50); });
  EXPECT_TRUE(has(e, "chunk table offset")) << e;
  e = error_after([&](std::string* b) { PutLE<int64_t>(b, point_data, -1); });
  EXPECT_TRUE(has(e, "chunk table offset")) << e;  // the last 8 bytes are no offset here
  // The 64-bit count of a LAS 1.4 file: 2^40.
  const std::string v14 = ReadBytes(DataPath("point-time-1.4.las.laz"));
  std::string b = v14;
  PutLE<uint32_t>(&b, 107, 0);
  PutLE<uint64_t>(&b, 247, uint64_t{1} << 40);
  WriteBytes(path, b);
  e = ReadError(path);
  EXPECT_TRUE(has(e, path) && has(e, "1099511627776")) << e;
}

TEST(LazRead, UnsupportedVlrsAreInputErrors) {
  const std::string bytes = ReadBytes(DataPath("1815.laz"));
  const size_t payload = LaszipPayload(bytes);
  TempDir dir;
  const std::string path = dir.File("vlr.laz");
  auto error_after = [&](const std::function<void(std::string*)>& edit) {
    std::string b = bytes;
    edit(&b);
    WriteBytes(path, b);
    return InputErrorMessage([&] { OpenPointReader(path); });
  };
  std::string e = error_after([&](std::string* b) { PutLE<uint16_t>(b, payload, 1); });
  EXPECT_NE(e.find("compressor 1"), std::string::npos) << e;
  EXPECT_NE(e.find(path), std::string::npos) << e;
  e = error_after([&](std::string* b) { PutLE<uint16_t>(b, payload + 34, 42); });
  EXPECT_NE(e.find("item type 42"), std::string::npos) << e;
  e = error_after([&](std::string* b) { PutLE<uint16_t>(b, payload + 34 + 4, 1); });
  EXPECT_NE(e.find("version 1"), std::string::npos) << e;
  e = error_after([&](std::string* b) { (*b)[payload - 54 + 2] = 'X'; });  // no laszip VLR
  EXPECT_NE(e.find("laszip encoded"), std::string::npos) << e;
}

}  // namespace
}  // namespace candi::io

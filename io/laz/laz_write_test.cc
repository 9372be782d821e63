// LAZ writing: the arithmetic encoder and integer compressor against their decoders, the chunk
// encoders against the chunk decoders (records built from a seeded RNG, and arbitrary bytes), the
// chunks of LAZ files written by LASzip re-encoded byte for byte, and whole files: LAS -> LAZ ->
// LAS bit for bit for point formats 0-3 and 6-8 with extra bytes, the same bytes on 1 and 2
// threads, an empty cloud, and no partial file on a failed write.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "core/binary_file.h"
#include "core/check.h"
#include "io/convert.h"
#include "io/las/las_header.h"
#include "io/las/las_io.h"
#include "io/laz/laz_arith.h"
#include "io/laz/laz_chunks.h"
#include "io/laz/laz_format.h"
#include "io/point_io.h"
#include "tests/util/las_bytes.h"
#include "tests/util/las_clouds.h"
#include "tests/util/laz_records.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

namespace util = ::candi::testing;
using util::LasPointRecords;
using util::OptionsFor;
using util::RandomCloud;
using util::ScanLikeRecords;
using util::LazRecords;
using util::ReadBytes;
using util::TempDir;

std::string LazDataPath(const std::string& name) {
  return util::SourceDir() + "/tests/data/laz/" + name;
}

// ---- The entropy coder ----

TEST(LazEncoder, SymbolsBitsAndRawValuesDecodeToTheirInput) {
  std::mt19937 rng(7);
  laz::SymbolModel small(5), large(300), decoded_small(5), decoded_large(300);
  laz::BitModel bit, decoded_bit;
  laz::ArithmeticEncoder enc;
  struct Op {
    int kind;
    uint32_t value, bits;
  };
  std::vector<Op> ops;
  for (int i = 0; i < 200000; ++i) {
    const int kind = static_cast<int>(rng() % 6);
    // Skewed symbols so that the models adapt and the interval shrinks fast (carries).
    const uint32_t skew = rng() % 8 == 0 ? rng() : rng() % 3;
    Op op{kind, 0, 0};
    switch (kind) {
      case 0:
        op.value = skew % 5;
        enc.EncodeSymbol(&small, op.value);
        break;
      case 1:
        op.value = skew % 300;
        enc.EncodeSymbol(&large, op.value);
        break;
      case 2:
        op.value = skew % 2;
        enc.EncodeBit(&bit, op.value);
        break;
      case 3:
        op.bits = 1 + rng() % 32;
        op.value = op.bits == 32 ? static_cast<uint32_t>(rng()) : rng() & ((1u << op.bits) - 1);
        enc.WriteBits(op.bits, op.value);
        break;
      case 4:
        op.value = rng() & 0xFFFF;
        enc.WriteShort(static_cast<uint16_t>(op.value));
        break;
      default:
        op.value = static_cast<uint32_t>(rng());
        enc.WriteInt(op.value);
        break;
    }
    ops.push_back(op);
  }
  enc.Done();
  laz::ArithmeticDecoder dec;
  dec.Init(enc.data(), enc.data() + enc.size());
  for (size_t i = 0; i < ops.size(); ++i) {
    const Op& op = ops[i];
    uint32_t got = 0;
    switch (op.kind) {
      case 0:
        got = dec.DecodeSymbol(&decoded_small);
        break;
      case 1:
        got = dec.DecodeSymbol(&decoded_large);
        break;
      case 2:
        got = dec.DecodeBit(&decoded_bit);
        break;
      case 3:
        got = dec.ReadBits(op.bits);
        break;
      case 4:
        got = dec.ReadShort();
        break;
      default:
        got = dec.ReadInt();
        break;
    }
    ASSERT_EQ(got, op.value) << "operation " << i << " of kind " << op.kind;
  }
  EXPECT_FALSE(dec.overrun());
  EXPECT_EQ(dec.consumed(), enc.size());  // Done() ends exactly where the decoder stops
}

TEST(LazEncoder, IntegersOfEveryWidthAndExtremeCorrectorsRoundTrip) {
  std::mt19937 rng(11);
  for (uint32_t bits : {8u, 16u, 32u}) {
    laz::IntegerCoder enc_ic(bits, 3), dec_ic(bits, 3);
    enc_ic.Init();
    dec_ic.Init();
    laz::ArithmeticEncoder enc;
    std::vector<std::array<int32_t, 3>> values;  // prediction, real, context
    const int32_t lo = bits == 32 ? INT32_MIN : 0;
    const int32_t hi = bits == 32 ? INT32_MAX : static_cast<int32_t>((1u << bits) - 1);
    for (int i = 0; i < 50000; ++i) {
      int32_t p = static_cast<int32_t>(rng()), r = static_cast<int32_t>(rng());
      if (bits < 32) p &= hi, r &= hi;
      if (i % 5 == 0) r = p + static_cast<int32_t>(rng() % 7) - 3;  // small correctors
      if (i % 97 == 0) p = lo, r = hi;                              // extremes
      if (i % 89 == 0) p = hi, r = lo;
      if (bits < 32) r &= hi;
      const int32_t context = static_cast<int32_t>(rng() % 3);
      values.push_back({p, r, context});
      enc_ic.Compress(&enc, p, r, static_cast<uint32_t>(context));
    }
    enc.Done();
    laz::ArithmeticDecoder dec;
    dec.Init(enc.data(), enc.data() + enc.size());
    for (size_t i = 0; i < values.size(); ++i) {
      const int32_t got =
          dec_ic.Decompress(&dec, values[i][0], static_cast<uint32_t>(values[i][2]));
      ASSERT_EQ(got, values[i][1]) << bits << " bits, value " << i;
    }
    EXPECT_FALSE(dec.overrun());
  }
}

TEST(LazEncoder, AResetModelCodesAsANewOne) {
  // A model's first distribution is made at its first symbol; after Reset() (and an integer
  // coder's second Init()) it must code, and decode, as a model just built.
  std::mt19937 rng(5);
  std::vector<uint32_t> symbols(3000);
  for (uint32_t& s : symbols) s = rng() % 7 == 0 ? rng() % 300 : rng() % 5;
  auto encode = [&](laz::SymbolModel* m, laz::IntegerCoder* ic) {
    laz::ArithmeticEncoder enc;
    for (uint32_t s : symbols) {
      enc.EncodeSymbol(m, s);
      ic->Compress(&enc, 150, static_cast<int32_t>(s));  // correctors of both signs
    }
    enc.Done();
    return std::vector<uint8_t>(enc.data(), enc.data() + enc.size());
  };
  laz::SymbolModel fresh(300), reused(300);
  laz::IntegerCoder fresh_ic(16), reused_ic(16);
  fresh_ic.Init();
  reused_ic.Init();
  const std::vector<uint8_t> first = encode(&reused, &reused_ic);  // both adapt to the symbols
  reused.Reset();
  reused_ic.Init();
  const std::vector<uint8_t> expected = encode(&fresh, &fresh_ic);
  EXPECT_TRUE(first == expected);
  EXPECT_TRUE(encode(&reused, &reused_ic) == expected);
  laz::SymbolModel dec_model(300);
  laz::IntegerCoder dec_ic(16);
  dec_ic.Init();
  for (int pass = 0; pass < 2; ++pass) {
    laz::ArithmeticDecoder dec;
    dec.Init(expected.data(), expected.data() + expected.size());
    for (size_t i = 0; i < symbols.size(); ++i) {
      ASSERT_EQ(dec.DecodeSymbol(&dec_model), symbols[i]) << "pass " << pass << ", symbol " << i;
      ASSERT_EQ(dec_ic.Decompress(&dec, 150), static_cast<int32_t>(symbols[i]));
    }
    dec_model.Reset();
    dec_ic.Init();
  }
}

// ---- Chunks ----

std::vector<uint8_t> EncodeChunk(const laz::Vlr& vlr, const uint8_t* records, uint32_t n) {
  std::vector<uint8_t> out;
  if (vlr.compressor == laz::kLayeredChunked) {
    laz::EncodeLayeredChunk(vlr.items, records, n, &out);
  } else {
    laz::EncodePointwiseChunk(vlr.items, records, n, &out);
  }
  return out;
}

std::vector<uint8_t> DecodeChunk(const laz::Vlr& vlr, const std::vector<uint8_t>& chunk,
                                 uint32_t n) {
  std::vector<uint8_t> out(static_cast<size_t>(n) * vlr.record_length());
  if (vlr.compressor == laz::kLayeredChunked) {
    laz::DecodeLayeredChunk(vlr.items, chunk.data(), chunk.size(), n, out.data());
  } else {
    laz::DecodePointwiseChunk(vlr.items, chunk.data(), chunk.size(), n, out.data());
  }
  return out;
}


const int kFormats[] = {0, 1, 2, 3, 6, 7, 8};

TEST(LazChunk, ScanLikeRecordsOfEveryFormatRoundTrip) {
  for (int format : kFormats) {
    for (int extra : {0, 5}) {
      const laz::Vlr vlr = laz::WriterVlr(format, extra, 50000);
      for (uint32_t n : {1u, 2u, 3u, 1000u, 20000u}) {
        const std::vector<uint8_t> records =
            ScanLikeRecords(format, extra, n, static_cast<uint32_t>(format * 100 + n));
        const std::vector<uint8_t> chunk = EncodeChunk(vlr, records.data(), n);
        ASSERT_TRUE(DecodeChunk(vlr, chunk, n) == records)
            << "format " << format << ", " << extra << " extra bytes, " << n << " points";
        if (n == 20000) {
          EXPECT_LT(chunk.size(), records.size() / 2) << "format " << format;
        }
      }
    }
  }
}

TEST(LazChunk, ArbitraryBytesRoundTrip) {
  // Every record byte random: NaN and negative-zero times, channel switches at every point,
  // return numbers beyond the returns, all flags.
  std::mt19937 rng(3);
  for (int format : kFormats) {
    const laz::Vlr vlr = laz::WriterVlr(format, 3, 50000);
    const uint32_t n = 5000;
    std::vector<uint8_t> records(static_cast<size_t>(n) * vlr.record_length());
    for (uint8_t& b : records) b = static_cast<uint8_t>(rng());
    for (uint32_t i = 0; i < n; i += 7) {  // some runs of equal records
      std::memcpy(&records[(i + 1) * vlr.record_length() % records.size()],
                  &records[i * vlr.record_length()], vlr.record_length());
    }
    const std::vector<uint8_t> chunk = EncodeChunk(vlr, records.data(), n);
    ASSERT_TRUE(DecodeChunk(vlr, chunk, n) == records) << "format " << format;
  }
}

TEST(LazChunk, AFieldThatChangesAtOneRecordIsStillCoded) {
  // The layered encoder does not code the layers of fields that are the same in every record of
  // the chunk (they are stored empty); a field that changes at a single record (the second, a
  // middle one, the last) must still be coded.
  struct Field {
    const char* name;
    size_t offset;
    uint8_t flip;  // the bits changed
  };
  for (int format : {6, 7, 8}) {
    const laz::Vlr vlr = laz::WriterVlr(format, 0, 50000);
    const size_t length = vlr.record_length();
    const uint32_t n = 600;
    std::vector<uint8_t> constant = ScanLikeRecords(format, 0, n, static_cast<uint32_t>(format));
    std::vector<Field> fields = {{"intensity", 12, 0x01}, {"intensity high", 13, 0x80},
                                 {"flags", 15, 0x81},     {"classification", 16, 0x02},
                                 {"user data", 17, 0x04}};
    if (format >= 7) fields.push_back({"green", 32, 0x01});
    if (format == 8) fields.push_back({"NIR", 37, 0x10});
    for (uint32_t i = 1; i < n; ++i) {  // every field as in the first record
      for (const Field& f : fields) constant[i * length + f.offset] = constant[f.offset];
    }
    ASSERT_TRUE(DecodeChunk(vlr, EncodeChunk(vlr, constant.data(), n), n) == constant);
    for (const Field& f : fields) {
      for (uint32_t at : {1u, n / 2, n - 1}) {
        std::vector<uint8_t> records = constant;
        records[at * length + f.offset] ^= f.flip;
        const std::vector<uint8_t> chunk = EncodeChunk(vlr, records.data(), n);
        EXPECT_TRUE(DecodeChunk(vlr, chunk, n) == records)
            << "format " << format << ", " << f.name << " changed at record " << at;
      }
    }
  }
}

TEST(LazChunkWriter, PiecesAndBatchesDoNotChangeTheBytes) {
  // 10 chunks (two batches of LazChunkWriter::kBatchChunks = 8, the last chunk short), added at
  // once or in odd pieces: the same chunks, each the chunk encoder's bytes for its records.
  const uint32_t n = 8 * 50000 + 50000 + 123;
  const std::vector<uint8_t> records = ScanLikeRecords(1, 2, n, 9);
  const laz::Vlr vlr = laz::WriterVlr(1, 2, 50000);
  const size_t length = vlr.record_length();
  auto write = [&](size_t piece) {
    std::vector<uint8_t> out;
    LazChunkWriter writer(vlr, length, [&](const uint8_t* data, size_t size) {
      out.insert(out.end(), data, data + size);
    });
    for (size_t first = 0; first < n; first += piece) {
      writer.Add(records.data() + first * length, std::min<size_t>(piece, n - first));
    }
    const std::vector<uint8_t> table = writer.Finish();
    out.insert(out.end(), table.begin(), table.end());
    return out;
  };
  const std::vector<uint8_t> whole = write(n);
  EXPECT_TRUE(write(777) == whole);
  EXPECT_TRUE(write(50000) == whole);
  std::vector<uint8_t> expected;
  std::vector<uint32_t> sizes;
  for (uint32_t first = 0; first < n; first += 50000) {
    const uint32_t count = std::min<uint32_t>(50000, n - first);
    const std::vector<uint8_t> chunk = EncodeChunk(vlr, records.data() + first * length, count);
    expected.insert(expected.end(), chunk.begin(), chunk.end());
    sizes.push_back(static_cast<uint32_t>(chunk.size()));
  }
  EXPECT_EQ(sizes.size(), 10u);
  const std::vector<uint8_t> table = EncodeLazChunkTable(sizes);
  expected.insert(expected.end(), table.begin(), table.end());
  EXPECT_TRUE(whole == expected);
}

// ---- Chunks of files written by LASzip, re-encoded ----

struct ReencodeResult {
  size_t chunks = 0, identical = 0;
  bool table_identical = false;
  std::string first_difference;
};

// Decodes every chunk of a LAZ file and encodes its records again with candi's encoder.
ReencodeResult Reencode(const std::string& path) {
  BinaryFile file(path);
  LasHeader header = ReadLasHeader(&file);
  header.point_format &= 0x3F;
  const laz::Vlr vlr = util::LaszipVlrOf(&file, header);
  const std::vector<LazChunk> chunks = ReadLazChunkTable(
      file, vlr, header.offset_to_point_data, LasPointCount(header), header.record_length);
  ReencodeResult result;
  std::vector<uint32_t> sizes;
  for (const LazChunk& c : chunks) {
    std::vector<uint8_t> original(c.bytes);
    file.ReadAt(c.offset, original.data(), original.size());
    const std::vector<uint8_t> records = DecodeChunk(vlr, original, c.points);
    const std::vector<uint8_t> again = EncodeChunk(vlr, records.data(), c.points);
    EXPECT_TRUE(DecodeChunk(vlr, again, c.points) == records) << path << " chunk " << result.chunks;
    if (again == original) {
      ++result.identical;
    } else if (result.first_difference.empty()) {
      const auto at = std::mismatch(again.begin(), again.end(), original.begin(), original.end());
      result.first_difference = "chunk " + std::to_string(result.chunks) + ": " +
                                std::to_string(again.size()) + " bytes vs " +
                                std::to_string(original.size()) + ", first difference at byte " +
                                std::to_string(at.first - again.begin());
    }
    sizes.push_back(static_cast<uint32_t>(c.bytes));
    ++result.chunks;
  }
  if (!chunks.empty() && vlr.chunk_size != laz::kVariableChunkSize) {
    const std::vector<uint8_t> table = EncodeLazChunkTable(sizes);
    std::vector<uint8_t> stored(table.size());
    const uint64_t at = chunks.back().offset + chunks.back().bytes;
    file.ReadAt(at, stored.data(), stored.size());
    result.table_identical = stored == table;
  }
  return result;
}

TEST(LazChunk, LaszipWrittenChunksAreReencodedByteForByte) {
  // The LAZ files of tests/data/laz (tests/data/README.md), written by LAStools (1815,
  // extrabytes: formats 1 and 3 + extra bytes), TerraScan's LASzip (simple, point-time-1.4,
  // append-bug: formats 3, 1 and 8 + NIR + BYTE14), pylas (1_4_w_evlr: format 6) and a COPC
  // writer (simple.copc: format 7, variable chunks): every chunk comes out identical, and the
  // chunk table of the fixed-size ones too.
  for (const char* name : {"1815.laz", "extrabytes.laz", "simple.laz", "point-time-1.4.las.laz",
                           "append-bug.laz", "1_4_w_evlr.laz", "simple.copc.laz"}) {
    const ReencodeResult r = Reencode(LazDataPath(name));
    EXPECT_GT(r.chunks, 0u) << name;
    EXPECT_EQ(r.identical, r.chunks) << name << ": " << r.first_difference;
    if (std::string(name) != "simple.copc.laz") {
      EXPECT_TRUE(r.table_identical) << name;
    }
  }
}

TEST(LazChunk, SharedAutzenChunksAreReencodedByteForByte) {
  CANDI_REQUIRE_SHARED_DATA(path, "las/autzen_trim.laz");
  const ReencodeResult r = Reencode(path);
  EXPECT_EQ(r.chunks, 3u);
  EXPECT_EQ(r.identical, r.chunks) << r.first_difference;
  EXPECT_TRUE(r.table_identical);
}

// ---- Files ----


// The header of a file as its LAS twin would have it: no LAZ bit, the laszip VLR and the chunk
// table's offset not counted.
std::string ComparableHeader(const std::string& path) {
  BinaryFile file(path);
  LasHeader header = ReadLasHeader(&file);
  const bool laz = (header.point_format & 0x80) != 0;
  EXPECT_NE(laz, path.substr(path.size() - 4) == ".las") << path;
  header.point_format &= 0x3F;
  if (laz) {
    const std::vector<LasVlr> vlrs = ReadLasVlrs(&file, header);
    EXPECT_EQ(vlrs.back().user_id, "laszip encoded");
    EXPECT_EQ(vlrs.back().record_id, 22204);
    header.offset_to_point_data -= static_cast<uint32_t>(54 + vlrs.back().data.size());
    header.number_of_vlrs -= 1;
  }
  header.start_of_first_evlr = 0;
  return EncodeLasHeader(header);
}

TEST(LazWrite, LasToLazToLasIsBitForBitForEveryFormat) {
  for (int format : kFormats) {
    SCOPED_TRACE("point format " + std::to_string(format));
    TempDir dir;
    const PointCloud cloud = RandomCloud(format, 120001, 1000 + format);
    WritePointCloud(dir.File("a.las"), cloud, OptionsFor(format));
    const std::string a = ReadBytes(dir.File("a.las"));
    ASSERT_EQ(static_cast<int>(a[104]), format);
    // LAS -> LAZ
    WritePointCloud(dir.File("b.laz"), ReadPointCloud(dir.File("a.las")));
    const std::string las_records = LasPointRecords(a);
    ASSERT_EQ(LazRecords(dir.File("b.laz")), las_records);
    EXPECT_EQ(ComparableHeader(dir.File("b.laz")), ComparableHeader(dir.File("a.las")));
    // LAZ -> LAS
    WritePointCloud(dir.File("c.las"), ReadPointCloud(dir.File("b.laz")));
    const std::string c = ReadBytes(dir.File("c.las"));
    EXPECT_EQ(LasPointRecords(c), las_records);
    EXPECT_EQ(ComparableHeader(dir.File("c.las")), ComparableHeader(dir.File("a.las")));
    EXPECT_TRUE(c == a) << "the rewritten LAS file differs from the first";
    const size_t laz_bytes = ReadBytes(dir.File("b.laz")).size();
    std::printf("format %d: %zu points, LAS %.1f bytes/point, LAZ %.2f bytes/point\n", format,
                cloud.size(), static_cast<double>(a.size()) / cloud.size(),
                static_cast<double>(laz_bytes) / cloud.size());
  }
}

TEST(LazWrite, SharedDataLasToLazToLas) {
  for (const char* name :
       {"las/simple.las", "las/autzen_trim.las", "las/simple1_4.las", "las/1_4_w_evlr.las"}) {
    CANDI_REQUIRE_SHARED_DATA(path, name);
    SCOPED_TRACE(name);
    TempDir dir;
    WritePointCloud(dir.File("b.laz"), ReadPointCloud(path));
    WritePointCloud(dir.File("a.las"), ReadPointCloud(path));  // candi's LAS of the same points
    EXPECT_EQ(LazRecords(dir.File("b.laz")), LasPointRecords(ReadBytes(dir.File("a.las"))));
    EXPECT_EQ(ComparableHeader(dir.File("b.laz")), ComparableHeader(dir.File("a.las")));
    WritePointCloud(dir.File("c.las"), ReadPointCloud(dir.File("b.laz")));
    EXPECT_TRUE(ReadBytes(dir.File("c.las")) == ReadBytes(dir.File("a.las")));
  }
}

// Writes the LAS file as LAZ and compares the point data (chunks and chunk table) with that of
// `laz`, its twin written by another tool with 50,000-point chunks.
void ExpectPointDataOf(const std::string& las, const std::string& laz) {
  TempDir dir;
  WritePointCloud(dir.File("x.laz"), ReadPointCloud(las));
  // Only meaningful when candi's rewrite keeps every record byte.
  ASSERT_TRUE(LazRecords(dir.File("x.laz")) == LasPointRecords(ReadBytes(las))) << las;
  const std::string ours = ReadBytes(dir.File("x.laz")), theirs = ReadBytes(laz);
  const uint32_t a = util::GetLE<uint32_t>(ours, 96), b = util::GetLE<uint32_t>(theirs, 96);
  EXPECT_TRUE(ours.substr(a + 8) == theirs.substr(b + 8))
      << "point data of " << ours.size() - a << " vs " << theirs.size() - b << " bytes";
}

TEST(LazWrite, PointDataEqualsLaszipsForTheSameLasFile) {
  // (extrabytes.las is not among them: its undocumented and array extra bytes are not kept by
  // candi's points, so its LAS rewrite already differs; LazChunk tests cover its chunks.)
  ExpectPointDataOf(LazDataPath("1815.las"), LazDataPath("1815.laz"));  // LAStools las2las, format 1
  CANDI_REQUIRE_SHARED_DATA(simple, "las/simple.las");
  ExpectPointDataOf(simple, LazDataPath("simple.laz"));  // format 3
}

TEST(LazWrite, ConvertWritesLazWithTheCrsRecords) {
  // 1815.las states its CRS (NAD83(2011) / Texas Centric Lambert + NAVD88) in LASF_Projection
  // records; the LAZ keeps them, and a reprojection states the new CRS.
  TempDir dir;
  const std::string source = LazDataPath("1815.las");
  ConvertPointFile({}, source, dir.File("same.laz"));
  EXPECT_TRUE(LazRecords(dir.File("same.laz")) == LasPointRecords(ReadBytes(source)));
  EXPECT_EQ(OpenPointReader(dir.File("same.laz"))->info().meta.crs,
            OpenPointReader(source)->info().meta.crs);
  ConvertOptions options;
  options.to_crs = "EPSG:6588";  // NAD83(2011) / Texas South Central (ftUS)
  ConvertPointFile(options, source, dir.File("moved.laz"));
  const auto reader = OpenPointReader(dir.File("moved.laz"));
  EXPECT_NE(reader->info().meta.crs.find("6588"), std::string::npos) << reader->info().meta.crs;
  EXPECT_EQ(reader->info().count, 1247u);
}

// An independent reader: npm's laz-perf (WASM) under node decodes candi's LAZ of every format,
// with extra bytes and several chunks, to the records of the LAS twin. Skipped, saying so, where
// node or laz-perf is absent (scripts/deps.sh installs them).
TEST(LazWrite, LazPerfReadsCandisLaz) {
  std::string why;
  const std::string node = util::NodeWith("laz-perf", &why);
  if (node.empty()) GTEST_SKIP() << why << ": candi's LAZ is not checked by laz-perf";
  const std::string script = util::SourceDir() + "/tests/node/laz_perf_records.js";
  for (int format : kFormats) {
    SCOPED_TRACE("point format " + std::to_string(format));
    TempDir dir;
    const PointCloud cloud = RandomCloud(format, 60001, 77 + format);
    WritePointCloud(dir.File("a.las"), cloud, OptionsFor(format));
    WritePointCloud(dir.File("b.laz"), cloud, OptionsFor(format));
    const std::string command =
        node + " '" + script + "' '" + dir.File("b.laz") + "' '" + dir.File("b.bin") + "'";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    EXPECT_TRUE(ReadBytes(dir.File("b.bin")) == LasPointRecords(ReadBytes(dir.File("a.las"))));
  }
}

TEST(LazWrite, SameBytesOnOneAndTwoThreads) {
  TempDir dir;
  const PointCloud cloud = RandomCloud(3, 450000, 5);  // 9 chunks: two batches
  const auto bytes = util::WrittenOnOneAndTwoThreads(dir, ".laz", cloud, OptionsFor(3));
  EXPECT_TRUE(bytes[0] == bytes[1]);
}

TEST(LazWrite, EmptyCloud) {
  TempDir dir;
  for (int format : {0, 7}) {
    const PointCloud cloud = RandomCloud(format, 0, 1);
    const std::string path = dir.File("empty" + std::to_string(format) + ".laz");
    WritePointCloud(path, cloud, OptionsFor(format));
    const PointCloud back = ReadPointCloud(path);
    EXPECT_EQ(back.size(), 0u);
    const std::string bytes = ReadBytes(path);
    EXPECT_EQ(static_cast<uint8_t>(bytes[104]), 0x80 | format);
    // The point data: the table's offset, then a table of 0 chunks (as LASzip writes it).
    const uint32_t at = util::GetLE<uint32_t>(bytes, 96);
    EXPECT_EQ(util::GetLE<uint64_t>(bytes, at), at + 8u);
    EXPECT_EQ(bytes.size(), at + 16u);
  }
}

TEST(LazWrite, ReadOnlyFolderLeavesNoFile) {
  TempDir dir;
  const PointCloud cloud = RandomCloud(1, 1000, 2);
  if (geteuid() == 0) {
    // root writes into a folder of mode 0555; /proc refuses new files to everyone.
    EXPECT_THROW(WritePointCloud("/proc/candi_laz_write_test.laz", cloud, OptionsFor(1)),
                 InputError);
    EXPECT_FALSE(util::FileExists("/proc/candi_laz_write_test.laz"));
    return;
  }
  const std::string folder = dir.File("locked");
  std::filesystem::create_directory(folder);
  chmod(folder.c_str(), 0555);
  EXPECT_THROW(WritePointCloud(folder + "/out.laz", cloud, OptionsFor(1)), InputError);
  chmod(folder.c_str(), 0755);
  EXPECT_TRUE(std::filesystem::is_empty(folder));
}

TEST(LazWrite, InterruptedWriteLeavesNoPartialFile) {
  // A writer destroyed before Close() (an exception, an interrupt) removes its temporary file.
  TempDir dir;
  EXPECT_TRUE(util::InterruptedWriteLeavesNothing(dir, "cut.laz", RandomCloud(6, 60000, 4),
                                                  OptionsFor(6)));
}

}  // namespace
}  // namespace candi::io

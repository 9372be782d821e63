// COPC writing (a .copc.laz name): the file's layout (LAS 1.4, format 6-8, the copc info VLR
// first, variable-chunk laszip VLR, hierarchy EVLR), LAS -> COPC -> LAS as the same multiset of
// records for formats 6-8 and for the shared LAS files, formats 0-3 as 6/7, the octree's
// structure read from the file (every node's points inside its cube, counts summing to the
// header's, one point a cell of width spacing / 2^level), chunks decoded in any order, the same
// bytes on one and two threads, and no file left by an interrupted write.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include "core/binary_file.h"
#include "core/check.h"
#include "io/convert.h"
#include "io/copc/copc_write.h"
#include "io/las/las_header.h"
#include "io/las/las_io.h"
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
using util::ReadBytes;
using util::TempDir;

// A COPC file as its records say.
struct CopcFile {
  LasHeader header;
  std::vector<LasVlr> vlrs, evlrs;
  CopcInfo info;
  laz::Vlr laz;
  std::vector<CopcEntry> entries;  // of every page
  int pages = 0;
  std::string bytes;
};

// The node entries of the page at `offset` and of its child pages (entries of point count -1),
// each page inside the hierarchy EVLR's payload, into f->entries; the pages into f->pages.
void WalkPages(uint64_t offset, uint64_t size, CopcFile* f) {
  const uint64_t payload = f->header.start_of_first_evlr + 60;
  ASSERT_GE(offset, payload);
  ASSERT_LE(offset + size, payload + f->evlrs[0].data.size()) << "a page outside the EVLR";
  ++f->pages;
  const std::vector<CopcEntry> page = ParseCopcHierarchy(f->bytes.substr(offset, size));
  ASSERT_FALSE(page.empty());
  for (const CopcEntry& e : page) {
    if (e.points == -1) {
      WalkPages(e.offset, static_cast<uint64_t>(e.bytes), f);
    } else {
      f->entries.push_back(e);
    }
  }
}

CopcFile ReadCopc(const std::string& path) {
  CopcFile f;
  BinaryFile file(path);
  f.header = ReadLasHeader(&file);
  f.vlrs = ReadLasVlrs(&file, f.header);
  f.evlrs = ReadLasEvlrs(&file, f.header);
  f.bytes = ReadBytes(path);
  EXPECT_FALSE(f.vlrs.empty());
  if (f.vlrs.empty()) return f;
  EXPECT_EQ(f.vlrs[0].user_id, kCopcUserId);
  EXPECT_EQ(f.vlrs[0].record_id, kCopcInfoRecord);
  f.info = ParseCopcInfo(f.vlrs[0].data);
  for (const LasVlr& v : f.vlrs) {
    if (v.user_id == "laszip encoded") f.laz = laz::ParseVlr(v.data);
  }
  EXPECT_FALSE(f.evlrs.empty());
  if (f.evlrs.empty()) return f;
  WalkPages(f.info.root_hier_offset, f.info.root_hier_size, &f);
  return f;
}

// The records of a node's chunk, read from the file at the entry's offset.
std::string NodeRecords(const CopcFile& f, const CopcEntry& e) {
  std::string out(static_cast<size_t>(e.points) * f.header.record_length, '\0');
  laz::DecodeLayeredChunk(f.laz.items, reinterpret_cast<const uint8_t*>(f.bytes.data()) + e.offset,
                          e.bytes, e.points, reinterpret_cast<uint8_t*>(out.data()));
  return out;
}

std::vector<std::string> Sorted(const std::string& records, size_t length) {
  std::vector<std::string> v;
  for (size_t at = 0; at < records.size(); at += length) v.push_back(records.substr(at, length));
  std::sort(v.begin(), v.end());
  return v;
}

// The records of every node, the entries taken in `order`.
std::string AllNodeRecords(const CopcFile& f, const std::vector<size_t>& order) {
  std::string all;
  for (size_t j : order) all += NodeRecords(f, f.entries[j]);
  return all;
}

std::vector<size_t> InOrder(size_t n) {
  std::vector<size_t> order(n);
  for (size_t j = 0; j < n; ++j) order[j] = j;
  return order;
}

// The layout COPC 1.0 asks for, and the hierarchy's counts against the header's.
void ExpectCopcLayout(const CopcFile& f, int format) {
  EXPECT_EQ(f.header.version_minor, 4);
  EXPECT_EQ(f.header.header_size, 375);
  EXPECT_EQ(f.header.point_format, 0x80 | format);
  EXPECT_EQ(f.bytes.substr(377, 5), std::string("copc\0", 5))  // user id after 2 bytes
      << "the info VLR must follow the header";
  EXPECT_EQ(f.laz.chunk_size, laz::kVariableChunkSize);
  EXPECT_EQ(f.laz.compressor, laz::kLayeredChunked);
  ASSERT_FALSE(f.evlrs.empty());
  EXPECT_EQ(f.evlrs[0].user_id, kCopcUserId);
  EXPECT_EQ(f.evlrs[0].record_id, kCopcHierarchyRecord);
  // The root page is the hierarchy EVLR's last (child pages first, as untwine writes them).
  EXPECT_EQ(f.info.root_hier_offset + f.info.root_hier_size,
            f.header.start_of_first_evlr + 60 + f.evlrs[0].data.size());
  uint64_t sum = 0;
  for (const CopcEntry& e : f.entries) {
    EXPECT_GT(e.points, 0);
    sum += static_cast<uint64_t>(e.points);
  }
  EXPECT_EQ(sum, LasPointCount(f.header));
  ASSERT_FALSE(f.entries.empty());
  // The root page starts with the root node; every node is reached once.
  EXPECT_EQ(ParseCopcHierarchy(f.bytes.substr(f.info.root_hier_offset, 32))[0].key.level, 0);
  std::set<std::tuple<int, int, int, int>> keys;
  for (const CopcEntry& e : f.entries) {
    EXPECT_TRUE(keys.insert({e.key.level, e.key.x, e.key.y, e.key.z}).second) << "a node twice";
  }
  EXPECT_DOUBLE_EQ(f.info.spacing, 2.0 * f.info.halfsize / 128);
}

// Writes `cloud` as a.las (format `format`), converts it to b.copc.laz and checks the COPC's
// records, and those of its LAS rewrite c.las, against a.las's as multisets.
CopcFile RoundTrip(const TempDir& dir, const PointCloud& cloud, int format,
                   const ConvertOptions& convert = {}) {
  WritePointCloud(dir.File("a.las"), cloud, OptionsFor(format));
  ConvertPointFile(convert, dir.File("a.las"), dir.File("b.copc.laz"));
  CopcFile f = ReadCopc(dir.File("b.copc.laz"));
  ExpectCopcLayout(f, format);
  const std::vector<std::string> source =
      Sorted(LasPointRecords(ReadBytes(dir.File("a.las"))), f.header.record_length);
  EXPECT_TRUE(Sorted(AllNodeRecords(f, InOrder(f.entries.size())), f.header.record_length) ==
              source)
      << "the nodes' records";
  // candi's LAS reader reads it as a LAZ file (through the chunk table).
  EXPECT_TRUE(Sorted(util::LazRecords(dir.File("b.copc.laz")), f.header.record_length) == source);
  WritePointCloud(dir.File("c.las"), ReadPointCloud(dir.File("b.copc.laz")));
  EXPECT_TRUE(Sorted(LasPointRecords(ReadBytes(dir.File("c.las"))), f.header.record_length) ==
              source)
      << "COPC -> LAS";
  return f;
}

TEST(CopcWrite, LasToCopcToLasKeepsEveryRecordForFormats678) {
  for (int format : {6, 7, 8}) {
    SCOPED_TRACE("point format " + std::to_string(format));
    TempDir dir;
    // A scan-like walk with far jumps: a deep, sparse tree; extra bytes after the record.
    const CopcFile f = RoundTrip(dir, RandomCloud(format, 60001, 300 + format), format);
    EXPECT_EQ(f.header.scale, Eigen::Vector3d::Constant(0.001));
    EXPECT_GT(f.entries.size(), 10u);
    int depth = 0;
    for (const CopcEntry& e : f.entries) depth = std::max(depth, e.key.level);
    std::printf("format %d, scan-like walk of 60001 points: %zu nodes, depth %d\n", format,
                f.entries.size(), depth);
  }
}

// A 100 m x 60 m wavy floor of n points carrying format 7's attributes.
PointCloud FloorCloud(size_t n, uint32_t seed) {
  PointCloud cloud = RandomCloud(7, n, seed);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (size_t i = 0; i < n; ++i) {
    const double x = 100.0 * u(rng), y = 60.0 * u(rng);
    const Eigen::Vector3d world(500000.0 + x, 4500000.0 + y,
                                std::sin(0.2 * x) + 0.3 * std::cos(0.5 * y) + 0.01 * u(rng));
    cloud.positions[i] = cloud.frame.ToLocal(world);
  }
  return cloud;
}

// Every node's parent is a node, its points lie inside its cube, and those of octants with a
// child node lie one a cell of width spacing / 2^level. Returns the depth; *checked: the points
// checked one a cell.
int ExpectNodesInsideCubesOnePerCell(const CopcFile& f, size_t* checked) {
  const LasHeader& h = f.header;
  int depth = 0;
  *checked = 0;
  std::set<std::tuple<int, int, int, int>> keys, keys_all;
  for (const CopcEntry& e : f.entries) keys_all.insert({e.key.level, e.key.x, e.key.y, e.key.z});
  for (const CopcEntry& e : f.entries) {
    EXPECT_TRUE(keys.insert({e.key.level, e.key.x, e.key.y, e.key.z}).second);
    if (e.key.level > 0) {
      EXPECT_TRUE(keys_all.count({e.key.level - 1, e.key.x / 2, e.key.y / 2, e.key.z / 2}))
          << "a node without its parent";
    }
    depth = std::max(depth, e.key.level);
    const double width = 2.0 * f.info.halfsize / (1 << e.key.level);
    const double cell = f.info.spacing / (1 << e.key.level);  // halves per level
    const Eigen::Vector3d lo = f.info.center.array() - f.info.halfsize +
                               width * Eigen::Vector3d(e.key.x, e.key.y, e.key.z).array();
    const std::string records = NodeRecords(f, e);
    std::set<std::tuple<int64_t, int64_t, int64_t>> cells;
    for (size_t at = 0; at < records.size(); at += h.record_length) {
      Eigen::Vector3d w;
      for (int k = 0; k < 3; ++k)
        w[k] = util::GetLE<int32_t>(records, at + 4 * k) * h.scale[k] + h.offset[k];
      for (int k = 0; k < 3; ++k) {
        EXPECT_GE(w[k], lo[k] - 1e-6) << "level " << e.key.level;
        EXPECT_LE(w[k], lo[k] + width + 1e-6) << "level " << e.key.level;
      }
      // A point within 1 um of a cell's face may be on either side of it (rounding): skipped.
      const Eigen::Vector3d u = (w - lo) / cell;
      const Eigen::Vector3d a = (u.array() - 1e-6 / cell).floor(),
                            b = (u.array() + 1e-6 / cell).floor();
      if (a != b) continue;
      const Eigen::Vector3d c = a.array().max(0.0).min(127.0);
      // Points of octants without a child node may have been kept as a small octant: only the
      // others were chosen one a cell.
      const CopcKey child{e.key.level + 1, 2 * e.key.x + (c.x() >= 64), 2 * e.key.y + (c.y() >= 64),
                          2 * e.key.z + (c.z() >= 64)};
      if (!keys_all.count({child.level, child.x, child.y, child.z})) continue;
      ++*checked;
      EXPECT_TRUE(cells.insert({int64_t(c.x()), int64_t(c.y()), int64_t(c.z())}).second)
          << "two points in one cell of width " << cell << " at level " << e.key.level;
    }
  }
  return depth;
}

TEST(CopcWrite, EveryNodeInsideItsCubeOnePointACellSpacingHalvingPerLevel) {
  TempDir dir;
  const size_t n = 300000;
  const CopcFile f = RoundTrip(dir, FloorCloud(n, 11), 7);
  EXPECT_NEAR(f.info.halfsize, 50.0, 0.01);
  size_t checked = 0;
  const int depth = ExpectNodesInsideCubesOnePerCell(f, &checked);
  const double bytes = static_cast<double>(f.bytes.size());
  std::printf(
      "floor of %zu points: %zu nodes, depth %d, root spacing %.4f m, COPC %.2f bytes/point "
      "(LAS %.1f)\n",
      n, f.entries.size(), depth, f.info.spacing, bytes / n,
      static_cast<double>(ReadBytes(dir.File("a.las")).size()) / n);
  EXPECT_GE(depth, 2);
  EXPECT_GT(checked, n / 10) << "points checked one a cell";
}

TEST(CopcWrite, ChunksReadInAnyOrderGiveTheSamePoints) {
  TempDir dir;
  const CopcFile f = RoundTrip(dir, FloorCloud(50000, 5), 7);
  std::vector<size_t> order = InOrder(f.entries.size());
  const std::vector<std::string> forward = Sorted(AllNodeRecords(f, order), f.header.record_length);
  std::reverse(order.begin(), order.end());
  EXPECT_TRUE(Sorted(AllNodeRecords(f, order), f.header.record_length) == forward);
  std::shuffle(order.begin(), order.end(), std::mt19937(3));
  EXPECT_TRUE(Sorted(AllNodeRecords(f, order), f.header.record_length) == forward);
  // Each node alone: its chunk decodes to the records it held when read first.
  for (size_t j : order) {
    EXPECT_EQ(NodeRecords(f, f.entries[j]).size(),
              static_cast<size_t>(f.entries[j].points) * f.header.record_length);
  }
}

// The records of `las` as candi's LAS writer converts them to LAS 1.4 point format `format`.
std::vector<std::string> RecordsAsFormat(const TempDir& dir, const std::string& las, int format) {
  PointWriteOptions options;
  options.las_point_format = format;
  options.las_version_minor = 4;
  WritePointCloud(dir.File("as_format.las"), ReadPointCloud(las), options);
  const std::string bytes = ReadBytes(dir.File("as_format.las"));
  return Sorted(LasPointRecords(bytes), util::GetLE<uint16_t>(bytes, 105));
}

// The COPC's records and those of its LAS rewrite against `expected`.
void ExpectRecords(const TempDir& dir, const CopcFile& f, const std::string& copc,
                   const std::vector<std::string>& expected) {
  const size_t length = f.header.record_length;
  EXPECT_TRUE(Sorted(AllNodeRecords(f, InOrder(f.entries.size())), length) == expected);
  WritePointCloud(dir.File("back.las"), ReadPointCloud(copc));
  EXPECT_TRUE(Sorted(LasPointRecords(ReadBytes(dir.File("back.las"))), length) == expected)
      << "COPC -> LAS";
  // The LAS file does not claim to be COPC: the source's copc records are not carried over.
  BinaryFile back(dir.File("back.las"));
  const LasHeader header = ReadLasHeader(&back);
  for (const std::vector<LasVlr>& records :
       {ReadLasVlrs(&back, header), ReadLasEvlrs(&back, header)}) {
    for (const LasVlr& v : records) EXPECT_NE(v.user_id, kCopcUserId);
  }
}

TEST(CopcWrite, LegacyFormatsBecome6And7AsPdalDoes) {
  for (int format : {0, 1, 2, 3}) {
    SCOPED_TRACE("point format " + std::to_string(format));
    TempDir dir;
    WritePointCloud(dir.File("a.las"), RandomCloud(format, 20000, 40 + format), OptionsFor(format));
    ConvertPointFile({}, dir.File("a.las"), dir.File("b.copc.laz"));
    const CopcFile f = ReadCopc(dir.File("b.copc.laz"));
    const int copc_format = format >= 2 ? 7 : 6;
    ExpectCopcLayout(f, copc_format);
    ExpectRecords(dir, f, dir.File("b.copc.laz"),
                  RecordsAsFormat(dir, dir.File("a.las"), copc_format));
  }
}

// The COPC's CRS against its source's: the same WKT, or for GeoTIFF keys ("EPSG:n[+v]") the WKT
// of that code, with no GeoTIFF record left (LAS 1.4 formats 6-8 state the CRS as WKT only).
void ExpectSameCrs(const std::string& crs, const std::string& copc_crs, const CopcFile& f) {
  if (crs.rfind("EPSG:", 0) != 0) {
    EXPECT_EQ(copc_crs, crs);
    return;
  }
  const std::string code = crs.substr(5, crs.find_first_not_of("0123456789", 5) - 5);
  EXPECT_NE(copc_crs.find("\"EPSG\",\"" + code + "\""), std::string::npos)
      << crs << " -> " << copc_crs;
  for (const LasVlr& v : f.vlrs) {
    EXPECT_FALSE(v.user_id == "LASF_Projection" && v.record_id >= 34735 && v.record_id <= 34737);
  }
  EXPECT_TRUE(f.header.global_encoding & 0x10) << "the WKT bit";
}

TEST(CopcWrite, GeoTiffKeysBecomeWkt) {
  // 1815.las states NAD83(2011) / Texas Centric Lambert + NAVD88 in GeoTIFF keys.
  TempDir dir;
  const std::string source = util::SourceDir() + "/tests/data/laz/1815.las";
  ConvertPointFile({}, source, dir.File("b.copc.laz"));
  const CopcFile f = ReadCopc(dir.File("b.copc.laz"));
  ExpectCopcLayout(f, 6);  // from format 1
  const std::string crs = OpenPointReader(source)->info().meta.crs;
  ASSERT_EQ(crs.rfind("EPSG:", 0), 0u) << crs;
  ExpectSameCrs(crs, OpenPointReader(dir.File("b.copc.laz"))->info().meta.crs, f);
  ExpectRecords(dir, f, dir.File("b.copc.laz"), RecordsAsFormat(dir, source, 6));
}

TEST(CopcWrite, SharedLasFilesKeepEveryRecordAndTheirCrs) {
  for (const char* name :
       {"las/simple.las", "las/autzen_trim.las", "las/simple1_4.las", "las/1_4_w_evlr.las"}) {
    CANDI_REQUIRE_SHARED_DATA(path, name);
    SCOPED_TRACE(name);
    TempDir dir;
    ConvertPointFile({}, path, dir.File("b.copc.laz"));
    const CopcFile f = ReadCopc(dir.File("b.copc.laz"));
    const int format = f.header.point_format & 0x3F;
    ExpectCopcLayout(f, format);
    // Formats 6-8 keep their records; 0-3 are those of candi's LAS 1.4 rewrite as 6 or 7.
    ExpectRecords(dir, f, dir.File("b.copc.laz"), RecordsAsFormat(dir, path, format));
    // The CRS, as WKT: GeoTIFF keys ("EPSG:n") become the WKT of that code.
    const std::string crs = OpenPointReader(path)->info().meta.crs;
    const std::string copc_crs = OpenPointReader(dir.File("b.copc.laz"))->info().meta.crs;
    ExpectSameCrs(crs, copc_crs, f);
    std::printf("%s: CRS %s\n", name, crs.substr(0, 40).c_str());
    std::printf("%s: %llu points, %zu nodes\n", name,
                static_cast<unsigned long long>(LasPointCount(f.header)), f.entries.size());
  }
}

// The number after "\"key\":" in a JSON line, or -1.
double JsonNumber(const std::string& json, const std::string& key) {
  const size_t at = json.find("\"" + key + "\":");
  return at == std::string::npos ? -1.0 : std::atof(json.c_str() + at + key.size() + 3);
}

// An independent reader: npm's copc (copc.js, decoding with laz-perf's WASM build) under node
// reads candi's COPC: the header's count and format, the info VLR, the hierarchy, and every
// node's points equal to the source's records. Skipped, saying so, where node or copc is absent
// (scripts/deps.sh installs them).
// copc.js (under `node`) reads dir's b.copc.laz, written from a.las: the header's count and
// format, every node through the hierarchy's pages, and the nodes' records equal to a.las's.
void ExpectCopcJsReads(const std::string& node, const TempDir& dir, int format) {
  const std::string script = util::SourceDir() + "/tests/node/copc_records.js";
  const CopcFile f = ReadCopc(dir.File("b.copc.laz"));
  const std::string command = node + " '" + script + "' '" + dir.File("b.copc.laz") + "' '" +
                              dir.File("b.bin") + "' > '" + dir.File("b.json") + "'";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const std::string json = ReadBytes(dir.File("b.json"));
  const double count = static_cast<double>(LasPointCount(f.header));
  EXPECT_EQ(JsonNumber(json, "count"), count) << json;
  EXPECT_EQ(JsonNumber(json, "pointSum"), count) << json;
  EXPECT_EQ(JsonNumber(json, "format"), format) << json;
  EXPECT_EQ(JsonNumber(json, "nodes"), static_cast<double>(f.entries.size())) << json;
  EXPECT_DOUBLE_EQ(JsonNumber(json, "spacing"), f.info.spacing) << json;
  const size_t length = f.header.record_length;
  EXPECT_TRUE(Sorted(ReadBytes(dir.File("b.bin")), length) ==
              Sorted(LasPointRecords(ReadBytes(dir.File("a.las"))), length));
}

TEST(CopcWrite, CopcJsReadsCandisCopc) {
  std::string why;
  const std::string node = util::NodeWith("copc", &why);
  if (node.empty()) GTEST_SKIP() << why << ": candi's COPC is not checked by copc.js";
  for (int format : {6, 7, 8, 0}) {  // 0: a file of no point, format 6
    SCOPED_TRACE("point format " + std::to_string(format));
    TempDir dir;
    PointCloud cloud = format == 7   ? FloorCloud(80000, 21)
                       : format == 0 ? RandomCloud(6, 0, 1)
                                     : RandomCloud(format, 30001, 50 + format);
    if (format == 0) format = 6;
    WritePointCloud(dir.File("a.las"), cloud, OptionsFor(format));
    ConvertPointFile({}, dir.File("a.las"), dir.File("b.copc.laz"));
    ExpectCopcJsReads(node, dir, format);
  }
}

// Pages forced small: every node reached through child pages (by this file's walk and by
// copc.js), the counts summing to the header's, each node inside its cube one point a cell of
// width spacing / 2^level, chunks decoded in a shuffled order giving the source's records; the
// nodes and chunks those of the one-page file, only the hierarchy differs.
TEST(CopcWrite, ChildHierarchyPagesReachEveryNode) {
  std::string why;
  const std::string node = util::NodeWith("copc", &why);
  const size_t n = 150000;
  for (const auto& [levels, min_nodes] : {std::pair{1, 0}, std::pair{2, 3}}) {
    SCOPED_TRACE("page_levels " + std::to_string(levels) + ", min_page_nodes " +
                 std::to_string(min_nodes));
    TempDir dir;
    ConvertOptions convert;
    convert.write.copc.page_levels = levels;
    convert.write.copc.min_page_nodes = min_nodes;
    const CopcFile f = RoundTrip(dir, FloorCloud(n, 13), 7, convert);
    if (levels == 1 && min_nodes == 0) {
      EXPECT_EQ(static_cast<size_t>(f.pages), f.entries.size()) << "a page a node";
    }
    EXPECT_GT(f.pages, 1);
    size_t checked = 0;
    EXPECT_GE(ExpectNodesInsideCubesOnePerCell(f, &checked), 2);
    EXPECT_GT(checked, n / 10);
    std::vector<size_t> order = InOrder(f.entries.size());
    std::shuffle(order.begin(), order.end(), std::mt19937(levels));
    EXPECT_TRUE(Sorted(AllNodeRecords(f, order), f.header.record_length) ==
                Sorted(LasPointRecords(ReadBytes(dir.File("a.las"))), f.header.record_length));
    ConvertPointFile({}, dir.File("a.las"), dir.File("one.copc.laz"));
    const CopcFile one = ReadCopc(dir.File("one.copc.laz"));
    EXPECT_EQ(one.pages, 1);
    auto entries = [](const CopcFile& g) {
      std::set<std::tuple<int, int, int, int, uint64_t, int, int>> s;
      for (const CopcEntry& e : g.entries)
        s.insert({e.key.level, e.key.x, e.key.y, e.key.z, e.offset, e.bytes, e.points});
      return s;
    };
    EXPECT_TRUE(entries(f) == entries(one));
    std::printf("%zu points, pages of %d levels, %d nodes: %zu nodes in %d pages\n", n, levels,
                min_nodes, f.entries.size(), f.pages);
    if (node.empty()) {
      std::printf("%s: the pages are not checked by copc.js\n", why.c_str());
    } else {
      ExpectCopcJsReads(node, dir, 7);
    }
  }
}

TEST(CopcWriteOptions, DefaultsPassAndBadPagesAreRefused) {
  EXPECT_NO_THROW(CopcWriteOptions{}.Check());
  CopcWriteOptions options;
  options.page_levels = 0;
  EXPECT_THROW(options.Check(), std::invalid_argument);
  options = {};
  options.min_page_nodes = -1;
  EXPECT_THROW(options.Check(), std::invalid_argument);
}

// Every node of the complete octree below `key` down to `last_level`.
void AddSubtree(const CopcKey& key, int last_level, std::vector<CopcEntry>* entries) {
  entries->push_back({key, 1000 + 10 * entries->size(), 10, 1});
  if (key.level == last_level) return;
  for (int o = 0; o < 8; ++o) {
    AddSubtree({key.level + 1, 2 * key.x + (o & 1), 2 * key.y + (o >> 1 & 1), 2 * key.z + (o >> 2)},
               last_level, entries);
  }
}

// Untwine's defaults: levels 0-4 in the root page; node (4, 0, 0, 0)'s subtree of 73 nodes
// (down to level 6) in a page of its own, node (4, 1, 0, 0)'s of 9 (level 5) in the root page.
TEST(CopcWrite, DefaultPagesCutDeepSubtreesOfMoreThan50Nodes) {
  std::vector<CopcEntry> entries;
  AddSubtree({0, 0, 0, 0}, 4, &entries);
  ASSERT_EQ(entries.size(), 4681u);  // 1 + 8 + 64 + 512 + 4096
  std::vector<CopcEntry> deep, shallow;
  AddSubtree({4, 0, 0, 0}, 6, &deep);
  AddSubtree({4, 1, 0, 0}, 5, &shallow);
  entries.insert(entries.end(), deep.begin() + 1, deep.end());
  entries.insert(entries.end(), shallow.begin() + 1, shallow.end());
  std::shuffle(entries.begin(), entries.end(), std::mt19937(7));  // any order
  const CopcHierarchy h = EncodeCopcHierarchyPages({}, entries, 0);
  ASSERT_EQ(h.data.size(), 32u * (4681 + 8 + 73));
  const std::vector<CopcEntry> root = ParseCopcHierarchy(h.data.substr(h.root_offset));
  ASSERT_EQ(root.size(), 4689u);
  EXPECT_TRUE((root[0].key == CopcKey{0, 0, 0, 0}));
  int pointers = 0;
  for (const CopcEntry& e : root) {
    EXPECT_LE(e.key.level, 5);
    if (e.points != -1) continue;
    ++pointers;
    EXPECT_TRUE((e.key == CopcKey{4, 0, 0, 0}));
    const std::vector<CopcEntry> page = ParseCopcHierarchy(h.data.substr(e.offset, e.bytes));
    EXPECT_EQ(page.size(), 73u);
    EXPECT_TRUE((page[0].key == CopcKey{4, 0, 0, 0}) && page[0].points == 1);
  }
  EXPECT_EQ(pointers, 1);
}

// A root with two children, (1, 0, 0, 0) with a child: pages of one level, none small.
TEST(CopcWrite, HierarchyPagesPointToTheirChildPages) {
  const std::vector<CopcEntry> entries = {{{0, 0, 0, 0}, 1000, 10, 5},
                                          {{1, 1, 0, 0}, 1010, 11, 6},
                                          {{1, 0, 0, 0}, 1021, 12, 7},
                                          {{2, 1, 1, 0}, 1033, 13, 8}};
  CopcWriteOptions options;
  options.page_levels = 1;
  options.min_page_nodes = 0;
  const uint64_t base = 5000;
  const CopcHierarchy h = EncodeCopcHierarchyPages(options, entries, base);
  ASSERT_EQ(h.data.size(), 32u * (4 + 3));  // four pages: every node, and 3 child-page entries
  EXPECT_EQ(h.root_offset + h.root_size, h.data.size()) << "the root page last";
  const std::vector<CopcEntry> root = ParseCopcHierarchy(h.data.substr(h.root_offset));
  ASSERT_EQ(root.size(), 3u);
  EXPECT_EQ(root[0].points, 5);
  // Children by octant: (1, 0, 0, 0) first.
  EXPECT_TRUE((root[1].key == CopcKey{1, 0, 0, 0}) && root[1].points == -1);
  EXPECT_TRUE((root[2].key == CopcKey{1, 1, 0, 0}) && root[2].points == -1);
  const std::vector<CopcEntry> page =
      ParseCopcHierarchy(h.data.substr(root[1].offset - base, root[1].bytes));
  ASSERT_EQ(page.size(), 2u);
  EXPECT_EQ(page[0].points, 7);
  EXPECT_EQ(page[0].offset, 1021u);
  EXPECT_TRUE((page[1].key == CopcKey{2, 1, 1, 0}) && page[1].points == -1);
  // One page when no subtree is large enough for its own.
  options.min_page_nodes = 50;
  EXPECT_EQ(EncodeCopcHierarchyPages(options, entries, base).data.size(), 32u * 4);
  EXPECT_THROW(EncodeCopcHierarchyPages(options, {entries[1]}, base), std::exception);
}

TEST(CopcWrite, SameBytesOnOneAndTwoThreads) {
  TempDir dir;
  const auto bytes =
      util::WrittenOnOneAndTwoThreads(dir, ".copc.laz", FloorCloud(120000, 8), OptionsFor(7));
  EXPECT_TRUE(bytes[0] == bytes[1]);
}

TEST(CopcWrite, InfoGpsTimeRangeLeavesNaNOutWhereverItLands) {
  // A NaN time, first in input order: the nodes reorder the records, and the info VLR's range
  // must come from the other times whichever record ends up first.
  TempDir dir;
  PointCloud cloud = RandomCloud(7, 20000, 21);
  ScalarField* gps = cloud.FindScalar(las_field::kGpsTime);
  ASSERT_NE(gps, nullptr);
  double lo = INFINITY, hi = -INFINITY;
  for (size_t i = 1; i < cloud.size(); ++i) {
    lo = std::min(lo, gps->Get(i));
    hi = std::max(hi, gps->Get(i));
  }
  gps->Set(0, std::nan(""));
  WritePointCloud(dir.File("t.copc.laz"), cloud);
  const CopcFile f = ReadCopc(dir.File("t.copc.laz"));
  EXPECT_EQ(f.info.gpstime_minimum, lo);
  EXPECT_EQ(f.info.gpstime_maximum, hi);
}

TEST(CopcWrite, CloseReportsTheOctreeThenTheChunks) {
  TempDir dir;
  const size_t n = 60001;
  const PointCloud cloud = RandomCloud(7, n, 17);
  std::vector<std::tuple<std::string, uint64_t, uint64_t>> reports;
  PointWriteOptions options;
  options.close_progress = [&](const std::string& stage, uint64_t done, uint64_t total) {
    reports.emplace_back(stage, done, total);
  };
  WritePointCloud(dir.File("p.copc.laz"), cloud, options);
  ASSERT_GE(reports.size(), 2u);
  std::vector<std::string> stages;
  for (size_t i = 0; i < reports.size(); ++i) {
    const auto& [stage, done, total] = reports[i];
    EXPECT_EQ(total, n) << stage;
    EXPECT_LE(done, total) << stage;
    if (stages.empty() || stages.back() != stage) {
      stages.push_back(stage);
    } else {
      EXPECT_GE(done, std::get<1>(reports[i - 1])) << stage << ": done never goes back";
    }
  }
  EXPECT_EQ(stages, (std::vector<std::string>{"octree", "chunks"}));
  EXPECT_EQ(std::get<1>(reports.back()), n) << "every point compressed";
  for (size_t i = 1; i < reports.size(); ++i) {
    if (std::get<0>(reports[i]) == "chunks") {
      EXPECT_EQ(std::get<1>(reports[i - 1]), n) << "every point's node settled before the chunks";
      break;
    }
  }
  // A plain LAS or LAZ has nothing to do at Close() worth reporting.
  reports.clear();
  WritePointCloud(dir.File("p.laz"), cloud, options);
  EXPECT_TRUE(reports.empty());
}

TEST(CopcWrite, AnEmptyCloudIsAValidCopcFileThatReadsAsEmpty) {
  // An empty layer of a build written as COPC: the hierarchy is the root alone, of 0 points.
  TempDir dir;
  PointCloud cloud = RandomCloud(7, 10, 5);
  cloud.Resize(0);
  const std::string path = dir.File("empty.copc.laz");
  WritePointCloud(path, cloud);
  const CopcFile f = ReadCopc(path);
  ASSERT_EQ(f.entries.size(), 1u);
  EXPECT_EQ(f.entries[0].key.level, 0);
  EXPECT_EQ(f.entries[0].points, 0);
  EXPECT_EQ(f.entries[0].bytes, 0);
  EXPECT_GT(f.info.halfsize, 0.0);
  EXPECT_EQ(ReadPointCloud(path).size(), 0u);
}

TEST(CopcWrite, InterruptedWriteLeavesNoPartialFile) {
  TempDir dir;
  EXPECT_TRUE(
      util::InterruptedWriteLeavesNothing(dir, "cut.copc.laz", FloorCloud(5000, 4), OptionsFor(7)));
}

TEST(CopcWrite, InfoAndHierarchyRecordsRoundTrip) {
  CopcInfo info;
  info.center = Eigen::Vector3d(1.5, -2.25, 3.0);
  info.halfsize = 64.0;
  info.spacing = 1.0;
  info.root_hier_offset = 123456789012ull;
  info.root_hier_size = 96;
  info.gpstime_minimum = -5.5;
  info.gpstime_maximum = 7.25;
  const std::string data = EncodeCopcInfo(info);
  ASSERT_EQ(data.size(), 160u);
  EXPECT_EQ(data.substr(72), std::string(88, '\0'));  // reserved
  const CopcInfo back = ParseCopcInfo(data);
  EXPECT_EQ(back.center, info.center);
  EXPECT_EQ(back.root_hier_offset, info.root_hier_offset);
  EXPECT_EQ(back.gpstime_maximum, info.gpstime_maximum);
  const std::vector<CopcEntry> entries = {
      {{0, 0, 0, 0}, 1000, 50, 7}, {{3, 7, 1, 2}, 1050, 0, 0}, {{1, 1, 0, 1}, 99, 32, -1}};
  const std::string page = EncodeCopcHierarchy(entries);
  ASSERT_EQ(page.size(), 96u);
  const std::vector<CopcEntry> parsed = ParseCopcHierarchy(page);
  ASSERT_EQ(parsed.size(), 3u);
  EXPECT_TRUE(parsed[1].key == entries[1].key);
  EXPECT_EQ(parsed[2].points, -1);
  EXPECT_EQ(parsed[0].offset, 1000u);
}

}  // namespace
}  // namespace candi::io

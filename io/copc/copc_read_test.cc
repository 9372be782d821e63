// A COPC file's hierarchy walked as a reader walks it (io/copc/copc_read.h): the counts of the
// writer's files add up whether the hierarchy is one page or a page a node; a file that is not
// COPC has no summary; a malformed info VLR or page is refused naming the file and the byte.
#include "io/copc/copc_read.h"

#include <gtest/gtest.h>

#include <numeric>
#include <string>

#include "core/check.h"
#include "io/point_io.h"
#include "tests/util/las_clouds.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

namespace util = ::candi::testing;
using util::OptionsFor;
using util::RandomCloud;
using util::ReadBytes;
using util::TempDir;

CopcSummary SummaryOf(const std::string& path) {
  const std::optional<CopcSummary> s =
      ReadCopcSummary(path, OpenPointReader(path)->info().meta.las);
  CANDI_CHECK(s.has_value()) << path << " is not COPC";
  return *s;
}

uint64_t Sum(const std::vector<uint64_t>& v) {
  return std::accumulate(v.begin(), v.end(), uint64_t{0});
}

// The byte offset of the copc info VLR's payload: the first VLR, after LAS 1.4's 375-byte header
// and the VLR's 54-byte header.
constexpr size_t kInfoAt = 375 + 54;

TEST(CopcRead, TheHierarchysCountsAddUpInOnePageOrAPageANode) {
  TempDir dir;
  const PointCloud cloud = RandomCloud(7, 60000, 31);
  PointWriteOptions one_page = OptionsFor(7), many = OptionsFor(7);
  one_page.copc.page_levels = 30;  // every node in the root page
  many.copc.page_levels = 1;       // a page for every node with children
  many.copc.min_page_nodes = 0;
  WritePointCloud(dir.File("one.copc.laz"), cloud, one_page);
  WritePointCloud(dir.File("many.copc.laz"), cloud, many);
  const CopcSummary one = SummaryOf(dir.File("one.copc.laz")),
                    paged = SummaryOf(dir.File("many.copc.laz"));
  EXPECT_EQ(one.pages, 1u);
  EXPECT_GT(paged.pages, 3u);
  for (const CopcSummary* s : {&one, &paged}) {
    EXPECT_EQ(s->points, cloud.size());
    EXPECT_EQ(Sum(s->points_by_level), s->points);
    EXPECT_EQ(Sum(s->nodes_by_level), s->nodes);
    ASSERT_GE(s->nodes_by_level.size(), 3u) << "a tree of several levels";
    EXPECT_EQ(s->nodes_by_level[0], 1u) << "one root";
    for (size_t l = 0; l < s->nodes_by_level.size(); ++l) {
      EXPECT_GE(s->nodes_by_level[l], 1u) << l;
      EXPECT_LE(s->nodes_by_level[l], uint64_t{1} << (3 * l)) << l;
    }
    EXPECT_GT(s->info.halfsize, 0.0);
    EXPECT_GT(s->info.spacing, 0.0);
  }
  // The same tree, however it is paged.
  EXPECT_EQ(one.nodes_by_level, paged.nodes_by_level);
  EXPECT_EQ(one.points_by_level, paged.points_by_level);
  EXPECT_EQ(one.empty_nodes, paged.empty_nodes);
  // A LAZ file is not COPC.
  WritePointCloud(dir.File("plain.laz"), cloud, OptionsFor(7));
  EXPECT_FALSE(ReadCopcSummary(dir.File("plain.laz"),
                               OpenPointReader(dir.File("plain.laz"))->info().meta.las));
}

TEST(CopcRead, AMalformedHierarchyIsRefusedNamingTheFileAndTheByte) {
  TempDir dir;
  const PointCloud cloud = RandomCloud(7, 20000, 32);
  PointWriteOptions many = OptionsFor(7);
  many.copc.page_levels = 1;
  many.copc.min_page_nodes = 0;
  WritePointCloud(dir.File("good.copc.laz"), cloud, many);
  const std::string good = ReadBytes(dir.File("good.copc.laz"));
  const CopcInfo info = ParseCopcInfo(good.substr(kInfoAt, 160));
  const CopcSummary s = SummaryOf(dir.File("good.copc.laz"));
  ASSERT_GT(s.pages, 1u);
  const LasMetadata las = OpenPointReader(dir.File("good.copc.laz"))->info().meta.las;
  // ReadCopcSummary of `path` with the metadata `meta` refuses naming the file and `what`.
  auto expect_refused = [](const std::string& path, const LasMetadata& meta,
                           const std::string& what) {
    try {
      ReadCopcSummary(path, meta);
      ADD_FAILURE() << what << ": accepted";
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find(path), std::string::npos) << message;
      EXPECT_NE(message.find(what), std::string::npos) << message;
    }
  };
  auto refused = [&](const std::string& name, const std::string& bytes, const std::string& what) {
    util::WriteBytes(dir.File(name), bytes);
    expect_refused(dir.File(name), las, what);
  };
  auto put_u64 = [](std::string* b, size_t at, uint64_t v) {
    for (int i = 0; i < 8; ++i) (*b)[at + i] = static_cast<char>(v >> (8 * i));
  };
  auto put_i32 = [](std::string* b, size_t at, int32_t v) {
    for (int i = 0; i < 4; ++i)
      (*b)[at + i] = static_cast<char>(static_cast<uint32_t>(v) >> (8 * i));
  };
  // The root page's offset and size as the info VLR gives them: past the end, and not whole
  // entries. (The summary reads the hierarchy through `las`'s info VLR, so these edit it.)
  LasMetadata edited = las;
  auto with_info = [&](uint64_t offset, uint64_t size) {
    CopcInfo i = info;
    i.root_hier_offset = offset;
    i.root_hier_size = size;
    edited.vlrs[0].data = EncodeCopcInfo(i);
  };
  auto refused_info = [&](const std::string& what) {
    expect_refused(dir.File("good.copc.laz"), edited, what);
  };
  ASSERT_EQ(las.vlrs[0].user_id, kCopcUserId);
  ASSERT_EQ(las.vlrs[0].data, good.substr(kInfoAt, 160));
  with_info(good.size() - 16, 32);
  refused_info("byte " + std::to_string(good.size() - 16) +
               ": COPC hierarchy page of 32 bytes runs past");
  with_info(info.root_hier_offset, info.root_hier_size - 4);
  refused_info("not whole 32-byte entries");
  edited.vlrs[0].data.resize(100);
  refused_info("100 bytes where COPC 1.0 has 160");
  // Entries of the root page: a key outside its level, a count below -1, a child page that is the
  // root page again, and a chunk past the end.
  const size_t root = static_cast<size_t>(info.root_hier_offset);
  size_t child = 0;  // the first entry of a child page
  const size_t entries = static_cast<size_t>(info.root_hier_size / 32);
  while (child < entries &&
         good.substr(root + 32 * child + 28, 4) != std::string("\xff\xff\xff\xff", 4)) {
    ++child;
  }
  ASSERT_LT(child, entries) << "the root page names a child page";
  const size_t entry = root + 32 * child;
  std::string b = good;
  put_i32(&b, entry + 4, 5);  // x = 5 at level 1
  refused("key.copc.laz", b,
          "byte " + std::to_string(entry) + ": COPC hierarchy entry of key 1-5-");
  b = good;
  put_i32(&b, entry + 28, -2);
  refused("count.copc.laz", b, "with -2 points");
  b = good;
  put_u64(&b, entry + 16, info.root_hier_offset);
  put_i32(&b, entry + 24, static_cast<int32_t>(info.root_hier_size));
  refused("loop.copc.laz", b,
          "byte " + std::to_string(root) + ": COPC hierarchy page reached twice");
  b = good;
  put_u64(&b, root + 16, good.size());  // the root node's chunk
  put_i32(&b, root + 24, 100);
  put_i32(&b, root + 28, 5);
  refused("chunk.copc.laz", b, "COPC node's chunk at byte " + std::to_string(good.size()));
}

}  // namespace
}  // namespace candi::io

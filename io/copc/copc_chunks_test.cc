// WriteCopcNodes, the octree's nodes of a COPC file each compressed into one layered LAZ chunk,
// bucket by bucket in parallel.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <map>
#include <stdexcept>
#include <tuple>
#include <vector>

#include "io/copc/copc_octree.h"
#include "io/copc/copc_write.h"
#include "io/laz/laz_format.h"
#include "tests/util/las_clouds.h"

namespace candi::io {
namespace {

namespace util = ::candi::testing;

const Eigen::Vector3d kScale = Eigen::Vector3d::Constant(0.001);

CopcRecords InMemory(const std::vector<uint8_t>& records, size_t n, const laz::Vlr& vlr) {
  CopcRecords in;
  in.data = records.data();
  in.n = n;
  in.record_length = vlr.record_length();
  return in;
}

struct Written {
  std::vector<uint8_t> bytes;
  CopcPointData data;
};

Written Write(const std::vector<uint8_t>& records, size_t n, const laz::Vlr& vlr,
              const CopcOctreeOptions& options, int threads) {
  Written w;
  tbb::task_arena(threads).execute([&] {
    w.data = WriteCopcNodes(
        options, InMemory(records, n, vlr), kScale, Eigen::Vector3d::Zero(), nullptr, vlr, 1000,
        [&](const uint8_t* p, size_t size) { w.bytes.insert(w.bytes.end(), p, p + size); });
  });
  return w;
}

TEST(CopcChunks, EachChunkIsItsNodesRecordsTheSameBytesOnAnyThreadCountOrBatch) {
  // The chunks come in the entries' order, one after another from the first offset, each its
  // node's records in input order; batches of one bucket, of a few or of all, on 1 and 2
  // threads, give the same bytes. Another bucket size gives the same chunks in another order.
  const size_t n = 60000;
  const std::vector<uint8_t> records = util::ScanLikeRecords(7, 0, n, 4);
  const laz::Vlr vlr = laz::WriterVlr(7, 0, 50000);
  const size_t length = vlr.record_length();
  CopcOctreeOptions options;
  options.bucket_points = 4000;
  const CopcOctree tree =
      BuildCopcOctree(options, records.data(), n, length, kScale, Eigen::Vector3d::Zero());
  std::map<std::tuple<int, int, int, int>, const CopcNode*> nodes;
  for (const CopcNode& node : tree.nodes) {
    nodes[{node.key.level, node.key.x, node.key.y, node.key.z}] = &node;
  }
  ASSERT_GE(tree.nodes.size(), 8u);
  const Written whole = Write(records, n, vlr, options, 1);
  ASSERT_EQ(whole.data.entries.size(), tree.nodes.size());
  uint64_t offset = 1000;
  std::map<std::tuple<int, int, int, int>, std::vector<uint8_t>> chunks;
  for (const CopcEntry& e : whole.data.entries) {
    ASSERT_EQ(e.offset, offset);
    const CopcNode& node = *nodes.at({e.key.level, e.key.x, e.key.y, e.key.z});
    ASSERT_EQ(static_cast<uint64_t>(e.points), node.size);
    std::vector<uint8_t> decoded(node.size * length);
    const uint8_t* chunk = whole.bytes.data() + (offset - 1000);
    laz::DecodeLayeredChunk(vlr.items, chunk, static_cast<size_t>(e.bytes),
                            static_cast<uint32_t>(e.points), decoded.data());
    for (size_t k = 0; k < node.size; ++k) {
      ASSERT_TRUE(std::equal(decoded.begin() + k * length, decoded.begin() + (k + 1) * length,
                             records.begin() + node.points[k] * length))
          << "node " << e.key.level << "-" << e.key.x << "-" << e.key.y << "-" << e.key.z;
    }
    chunks[{e.key.level, e.key.x, e.key.y, e.key.z}].assign(chunk, chunk + e.bytes);
    offset += static_cast<uint64_t>(e.bytes);
  }
  EXPECT_EQ(offset - 1000, whole.bytes.size());
  for (size_t batch : {size_t{1}, size_t{5000}}) {
    for (int threads : {1, 2}) {
      CopcOctreeOptions o = options;
      o.batch_points = batch;
      const Written w = Write(records, n, vlr, o, threads);
      EXPECT_TRUE(w.bytes == whole.bytes) << batch << " points a batch, " << threads << " threads";
      EXPECT_TRUE(w.data.chunk_table == whole.data.chunk_table);
    }
  }
  CopcOctreeOptions one_bucket = options;
  one_bucket.bucket_points = n;
  const Written other = Write(records, n, vlr, one_bucket, 2);
  ASSERT_EQ(other.data.entries.size(), whole.data.entries.size());
  EXPECT_FALSE(other.bytes == whole.bytes) << "one bucket: the nodes in another order";
  for (const CopcEntry& e : other.data.entries) {
    const uint8_t* chunk = other.bytes.data() + (e.offset - 1000);
    EXPECT_TRUE(std::equal(chunk, chunk + e.bytes,
                           chunks.at({e.key.level, e.key.x, e.key.y, e.key.z}).begin()));
  }
}

TEST(CopcChunks, ASinkThatFailsEndsTheWritingThere) {
  // A sink that fails (a full disk) at the third chunk: the error reaches the caller, and no
  // chunk is handed on after it.
  const size_t n = 30000;
  const std::vector<uint8_t> records = util::ScanLikeRecords(6, 0, n, 4);
  const laz::Vlr vlr = laz::WriterVlr(6, 0, 50000);
  CopcOctreeOptions options;
  options.bucket_points = 3000;
  options.batch_points = 1;
  for (int threads : {1, 2}) {
    int calls = 0;
    tbb::task_arena(threads).execute([&] {
      EXPECT_THROW(WriteCopcNodes(options, InMemory(records, n, vlr), kScale,
                                  Eigen::Vector3d::Zero(), nullptr, vlr, 0,
                                  [&](const uint8_t*, size_t) {
                                    if (++calls == 3) throw std::runtime_error("disk full");
                                  }),
                   std::runtime_error);
    });
    EXPECT_EQ(calls, 3) << threads << " threads";
  }
}

}  // namespace
}  // namespace candi::io

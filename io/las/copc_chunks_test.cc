// WriteCopcChunks, the chunk stage of a COPC file: each node's records compressed into one
// layered LAZ chunk, by batches of nodes in parallel.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <vector>

#include "io/las/copc_octree.h"
#include "io/las/copc_write.h"
#include "io/las/laz_format.h"
#include "tests/util/las_clouds.h"

namespace candi::io {
namespace {

namespace util = ::candi::testing;

TEST(CopcChunks, ManyBatchesAreTheBytesOfOneOnAnyThreadCount) {
  // Batches of one node, of a few, or all nodes in one, on 1 and 2 threads, must hand the sink
  // the same chunks in node order, each its node's records.
  const size_t n = 60000;
  const std::vector<uint8_t> records = util::ScanLikeRecords(7, 0, n, 4);
  const laz::Vlr vlr = laz::WriterVlr(7, 0, 50000);
  const size_t length = vlr.record_length();
  CopcPartition partition = PartitionCopcOctree({}, records.data(), n, length,
                                                Eigen::Vector3d::Constant(0.001),
                                                Eigen::Vector3d::Zero());
  const CopcOctree tree = partition.tree;
  const std::unique_ptr<uint8_t[]> sorted = RecordsByNode(&partition, records.data(), n, length);
  ASSERT_GE(tree.nodes.size(), 8u);
  struct Written {
    std::vector<uint8_t> bytes;
    CopcPointData data;
  };
  auto write = [&](size_t batch_points, int threads) {
    Written w;
    tbb::task_arena(threads).execute([&] {
      w.data = WriteCopcChunks(
          tree, sorted.get(), length, vlr, 1000,
          [&](const uint8_t* p, size_t size) { w.bytes.insert(w.bytes.end(), p, p + size); }, {},
          batch_points);
    });
    return w;
  };
  const Written whole = write(n, 1);
  ASSERT_EQ(whole.data.entries.size(), tree.nodes.size());
  uint64_t offset = 1000;
  const uint8_t* node_records = sorted.get();
  for (size_t j = 0; j < tree.nodes.size(); ++j) {
    const CopcEntry& e = whole.data.entries[j];
    ASSERT_EQ(e.offset, offset) << "node " << j;
    ASSERT_EQ(static_cast<uint64_t>(e.points), tree.nodes[j].size);
    std::vector<uint8_t> decoded(tree.nodes[j].size * length);
    laz::DecodeLayeredChunk(vlr.items, whole.bytes.data() + (offset - 1000),
                            static_cast<size_t>(e.bytes), static_cast<uint32_t>(e.points),
                            decoded.data());
    ASSERT_TRUE(std::equal(decoded.begin(), decoded.end(), node_records)) << "node " << j;
    node_records += decoded.size();
    offset += static_cast<uint64_t>(e.bytes);
  }
  for (size_t batch : {size_t{1}, size_t{5000}}) {
    for (int threads : {1, 2}) {
      const Written w = write(batch, threads);
      EXPECT_TRUE(w.bytes == whole.bytes) << batch << " points a batch, " << threads << " threads";
      EXPECT_TRUE(w.data.chunk_table == whole.data.chunk_table);
    }
  }
  // A sink that fails (a full disk) at the third chunk: the error reaches the caller, and no
  // chunk is handed on after it.
  for (int threads : {1, 2}) {
    int calls = 0;
    tbb::task_arena(threads).execute([&] {
      EXPECT_THROW(WriteCopcChunks(
                       tree, sorted.get(), length, vlr, 0,
                       [&](const uint8_t*, size_t) {
                         if (++calls == 3) throw std::runtime_error("disk full");
                       },
                       {}, 1),
                   std::runtime_error);
    });
    EXPECT_EQ(calls, 3) << threads << " threads";
  }
}

}  // namespace
}  // namespace candi::io

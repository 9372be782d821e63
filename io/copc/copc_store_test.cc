// A COPC file's records until Close() (io/copc/copc_store.h), through the writer: beyond the memory
// budget they are spilled beside the file and give the same bytes as in memory, the spill folder
// goes with the writer, and a count the disk cannot hold is refused before anything is written.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
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

TEST(CopcStore, ACountBeyondThisMachinesDiskIsRefusedBeforeAnythingIsWritten) {
  // 2^40 points: more than memory, so they would be spilled beside the file, and more than the
  // disk holds twice.
  TempDir dir;
  const PointCloud cloud = RandomCloud(7, 10, 3);
  const std::string path = dir.File("huge.copc.laz");
  const PointWriteSpec spec{cloud.schema, cloud.frame, cloud.meta, uint64_t{1} << 40};
  try {
    OpenPointWriter(path, spec);
    FAIL() << "10^12 points accepted";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(path), std::string::npos) << what;
    EXPECT_NE(what.find("1099511627776 points holds its records"), std::string::npos) << what;
    EXPECT_NE(what.find("GiB of disk"), std::string::npos) << what;
    EXPECT_NE(what.find("write LAZ"), std::string::npos) << what;
  }
  EXPECT_TRUE(std::filesystem::is_empty(dir.path())) << "no file and no spill folder left";
  // The same count as LAZ streams, so it opens (and, unclosed, leaves nothing either).
  { OpenPointWriter(dir.File("huge.laz"), spec); }
  EXPECT_FALSE(util::FileExists(dir.File("huge.laz")));
}

TEST(CopcStore, RecordsBeyondTheMemoryBudgetAreSpilledAndGiveTheSameBytes) {
  // A budget of 2 MB: 150,000 records of 36 bytes do not fit, so they go to a spill beside the
  // file (from the start when the count is stated; at the first chunk past the budget when it
  // is not) and the octree is built from there in groups of ~47,000 points. The bytes are those
  // of the file built in memory, and the spill folder is gone after Close(), or after a writer
  // destroyed before it.
  TempDir dir;
  const PointCloud cloud = RandomCloud(7, 150000, 12);
  PointWriteOptions spilled = OptionsFor(7);
  spilled.copc.memory_bytes = 2 << 20;
  WritePointCloud(dir.File("memory.copc.laz"), cloud, OptionsFor(7));
  const std::string expected = ReadBytes(dir.File("memory.copc.laz"));
  WritePointCloud(dir.File("stated.copc.laz"), cloud, spilled);
  {
    PointWriteSpec spec{cloud.schema, cloud.frame, cloud.meta, kUnknownCount};
    auto writer = OpenPointWriter(dir.File("streamed.copc.laz"), spec, spilled);
    const size_t piece = 20000;
    for (size_t first = 0; first < cloud.size(); first += piece) {
      PointCloud part;
      part.SetSchema(cloud.schema);
      part.frame = cloud.frame;
      part.meta = cloud.meta;
      for (size_t i = first; i < std::min(cloud.size(), first + piece); ++i) {
        part.AppendFrom(cloud, i);
      }
      writer->Write(part);
    }
    writer->Close();
  }
  for (const char* name : {"stated.copc.laz", "streamed.copc.laz"}) {
    std::string bytes = ReadBytes(dir.File(name)), want = expected;
    bytes.replace(90, 4, 4, '\0');  // the creation day and year
    want.replace(90, 4, 4, '\0');
    EXPECT_TRUE(bytes == want) << name;
  }
  size_t entries = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path())) {
    ++entries;
    EXPECT_EQ(e.path().extension(), ".laz") << e.path();
  }
  EXPECT_EQ(entries, 3u);
  TempDir cut;
  EXPECT_TRUE(util::InterruptedWriteLeavesNothing(cut, "cut.copc.laz", cloud, spilled));
}

}  // namespace
}  // namespace candi::io

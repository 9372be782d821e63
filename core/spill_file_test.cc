#include "core/spill_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstring>
#include <filesystem>
#include <numeric>
#include <string>
#include <vector>

#include "core/check.h"
#include "tests/util/test_util.h"

namespace candi {
namespace {

using testing::TempDir;

TEST(SpillFile, AppendedBytesMapAndReadBackAndTheFileGoesWithTheObject) {
  TempDir dir;
  const std::string path = dir.File("a.spill");
  std::vector<uint32_t> values(300000);
  std::iota(values.begin(), values.end(), 7u);
  {
    SpillRecords<uint32_t> spill(path);
    EXPECT_EQ(spill.count(), 0u);
    EXPECT_EQ(spill.Map().data(), nullptr) << "nothing appended: nothing to map";
    spill.Append(values.data(), 1000);
    spill.Append(values.data() + 1000, values.size() - 1000);
    EXPECT_EQ(spill.count(), values.size());
    const SpillFile::Mapping mapped = spill.Map();
    ASSERT_EQ(mapped.size(), values.size() * 4);
    EXPECT_EQ(std::memcmp(mapped.data(), values.data(), mapped.size()), 0);
    std::vector<uint32_t> part(5);
    spill.Read(123456, 5, part.data());
    EXPECT_EQ(part, std::vector<uint32_t>(values.begin() + 123456, values.begin() + 123461));
    EXPECT_TRUE(std::filesystem::exists(path));
  }
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(SpillFile, ADiscardedPrefixGivesItsBlocksBackAndKeepsTheRest) {
  TempDir dir;
  SpillFile spill(dir.File("b.spill"));
  const std::vector<uint8_t> bytes(8 << 20, 0xAB);
  spill.Append(bytes.data(), bytes.size());
  spill.Discard(5 << 20);
  spill.Discard(3 << 20);  // already given back: nothing
  EXPECT_EQ(spill.size(), bytes.size()) << "the size stays";
  std::vector<uint8_t> tail(1 << 20);
  spill.Read(7 << 20, tail.size(), tail.data());
  EXPECT_EQ(tail, std::vector<uint8_t>(1 << 20, 0xAB)) << "the bytes after the prefix are kept";
  // Where the filesystem punches holes (ext4, tmpfs), fewer blocks are allocated.
  const auto blocks = [&] {
    struct stat st;
    return stat(spill.path().c_str(), &st) == 0 ? static_cast<uint64_t>(st.st_blocks) * 512 : 0;
  };
  std::printf("%llu bytes on disk of %zu after the discard\n",
              static_cast<unsigned long long>(blocks()), bytes.size());
  EXPECT_LE(blocks(), bytes.size());
}

TEST(SpillFile, FailuresNameTheFile) {
  TempDir dir;
  // A folder that is not there: the first append cannot create the file.
  SpillFile missing(dir.File("no/such/folder/c.spill"));
  const uint8_t byte = 1;
  try {
    missing.Append(&byte, 1);
    FAIL() << "created in a missing folder";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no/such/folder/c.spill"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot create a spill file"), std::string::npos);
  }
  // A file-size limit fails the writes (EFBIG) the way a full disk does (ENOSPC).
  std::string error;
  {
    const testing::FileSizeLimit limit(1 << 20);
    SpillFile full(dir.File("d.spill"));
    const std::vector<uint8_t> block(1 << 16, 2);
    try {
      for (int i = 0; i < 64; ++i) full.Append(block.data(), block.size());
    } catch (const InputError& e) {
      error = e.what();
    }
  }
  EXPECT_NE(error.find("d.spill"), std::string::npos) << error;
  EXPECT_NE(error.find("cannot write a spill file: File too large"), std::string::npos) << error;
  EXPECT_TRUE(std::filesystem::is_empty(dir.path())) << "the files went with their objects";
}

}  // namespace
}  // namespace candi

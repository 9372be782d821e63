#include "core/atomic_file.h"

#include <gtest/gtest.h>

#include <sys/resource.h>

#include <csignal>
#include <filesystem>

#include "core/check.h"
#include "tests/util/test_util.h"

namespace candi {
namespace {

using testing::ReadBytes;
using testing::TempDir;

size_t Entries(const std::string& dir) {
  size_t n = 0;
  for (auto& e : std::filesystem::directory_iterator(dir)) n += e.is_regular_file();
  return n;
}

TEST(AtomicFile, CommitReplacesAndAbandonLeavesTheOldFile) {
  TempDir dir;
  WriteFileAtomic(dir.File("f"), "old");
  {
    AtomicFile f(dir.File("f"));
    f.Write("new, unfinished");
    EXPECT_EQ(ReadBytes(dir.File("f")), "old");
  }
  EXPECT_EQ(ReadBytes(dir.File("f")), "old");
  EXPECT_EQ(Entries(dir.path()), 1u) << "the temporary file is removed";
  AtomicFile g(dir.File("f"));
  g.Write("header.body");
  g.WriteAt(0, "HEADER", 6);
  g.Commit();
  EXPECT_EQ(ReadBytes(dir.File("f")), "HEADER.body");
}

TEST(AtomicFile, FailuresNameThePath) {
  TempDir dir;
  try {
    AtomicFile f(dir.File("missing/dir/f"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("missing/dir/f"), std::string::npos);
  }
  EXPECT_THROW(AtomicFile f(dir.path()), InputError);  // a directory
}

TEST(AtomicFile, AFailedWriteIsReportedAndTheDestinationKept) {
  // A file-size limit makes writes fail (EFBIG) the way a full disk does (ENOSPC), as any user.
  TempDir dir;
  WriteFileAtomic(dir.File("keep"), "precious");
  std::string error;
  {
    const testing::FileSizeLimit limit(1 << 20);
    try {
      AtomicFile f(dir.File("keep"));
      const std::string block(1 << 16, 'x');
      for (int i = 0; i < 64; ++i) f.Write(block);
      f.Commit();
    } catch (const InputError& e) {
      error = e.what();
    }
  }
  EXPECT_NE(error.find("write failed"), std::string::npos) << error;
  EXPECT_NE(error.find("destination is unchanged"), std::string::npos) << error;
  EXPECT_EQ(ReadBytes(dir.File("keep")), "precious");
  EXPECT_EQ(Entries(dir.path()), 1u) << "the temporary file is removed";
}

}  // namespace
}  // namespace candi

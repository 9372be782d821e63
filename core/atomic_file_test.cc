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

// A folder of this command's (here: one holding "mine") replaced; anything else refused; a
// symbolic link refused early and late, so the folder it points to is never left stale behind a
// new real folder.
bool HoldsMine(const std::string& p) { return std::filesystem::exists(p + "/mine"); }

TEST(ReplaceFolder, ReplacesItsOwnRefusesOthersAndLinks) {
  namespace fs = std::filesystem;
  TempDir dir;
  const std::string out = dir.File("out");
  auto build = [&](const std::string& text) {
    fs::create_directories(dir.File("tmp"));
    WriteFileAtomic(dir.File("tmp/mine"), text);
  };
  build("1");
  CheckReplaceableFolder(out, HoldsMine, "mine");
  ReplaceFolder(dir.File("tmp"), out, HoldsMine, "mine");
  build("2");
  CheckReplaceableFolder(out, HoldsMine, "mine");
  ReplaceFolder(dir.File("tmp"), out, HoldsMine, "mine");
  EXPECT_EQ(ReadBytes(out + "/mine"), "2");
  for (const auto& e : fs::directory_iterator(dir.path())) {
    EXPECT_EQ(e.path().filename().string().find(".candi-old-"), std::string::npos) << e.path();
  }
  fs::create_directories(dir.File("other"));
  EXPECT_THROW(CheckReplaceableFolder(dir.File("other"), HoldsMine, "mine"), InputError);
  fs::create_directory_symlink(out, dir.File("link"));
  build("3");
  for (int late = 0; late < 2; ++late) {
    try {
      if (late) {
        ReplaceFolder(dir.File("tmp"), dir.File("link"), HoldsMine, "mine");
      } else {
        CheckReplaceableFolder(dir.File("link"), HoldsMine, "mine");
      }
      ADD_FAILURE() << "a link was replaced";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("symbolic link"), std::string::npos) << e.what();
    }
  }
  EXPECT_TRUE(fs::is_symlink(dir.File("link")));
  EXPECT_EQ(ReadBytes(out + "/mine"), "2");
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

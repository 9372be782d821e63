// Shared helpers for candi's tests: paths to the repository, to ../shared/data, and temporary
// directories that clean up after themselves.
#pragma once

#include <gtest/gtest.h>

#include <string>

namespace candi::testing {

// The repository root (tests run from it; the path is also compiled in).
std::string SourceDir();
// ../shared/data/<relative> beside the repository, or "" when it is absent.
std::string SharedDataPath(const std::string& relative);
// The shell command that runs node with the npm packages scripts/deps.sh installs for the tests
// (tests/node/package.json, in .cache/node), or "" with *why set when node or `package` is
// absent (the test then skips, saying why).
std::string NodeWith(const std::string& package, std::string* why);

// While it lives, this process's writes past `bytes` of a file fail (EFBIG, SIGXFSZ ignored)
// the way they do on a full disk (ENOSPC), as any user; the limit and handler are restored after.
class FileSizeLimit {
 public:
  explicit FileSizeLimit(uint64_t bytes);
  ~FileSizeLimit();
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  uint64_t old_soft_ = 0;
  void (*old_handler_)(int) = nullptr;
};

// A fresh directory under $TMPDIR, removed with its contents on destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  std::string File(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

// Runs a shell command; stdout captured separately, then stdout + stderr together.
struct CommandResult {
  int code = -1;       // exit status (-1 when killed by a signal)
  std::string out;     // stdout
  std::string output;  // stdout then stderr
};
CommandResult RunCommand(const std::string& command);

// Writes bytes to a file (not atomic; for building test inputs).
void WriteBytes(const std::string& path, const std::string& bytes);
std::string ReadBytes(const std::string& path);
bool FileExists(const std::string& path);
// True when the environment sets CANDI_SLOW_TESTS=1.
bool SlowTestsEnabled();

}  // namespace candi::testing

// Skips the current test, naming the missing file, when ../shared/data/<relative> is absent.
#define CANDI_REQUIRE_SHARED_DATA(var, relative)                                          \
  const std::string var = ::candi::testing::SharedDataPath(relative);                     \
  if (var.empty()) {                                                                      \
    GTEST_SKIP() << "../shared/data/" << (relative) << " is absent (real data beside the " \
                 << "repository); skipping";                                              \
  }

// Skips the current test unless CANDI_SLOW_TESTS=1 (`make test-all` sets it; `make test` and CI do
// not): for real-data or long runs that would push CI past its time budget.
#define CANDI_REQUIRE_SLOW_TESTS()                                                     \
  if (!::candi::testing::SlowTestsEnabled()) {                                         \
    GTEST_SKIP() << "slow test: set CANDI_SLOW_TESTS=1 (make test-all) to run it";     \
  }

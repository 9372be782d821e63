#include "core/interrupt.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "tests/util/test_util.h"

namespace candi {
namespace {

namespace fs = std::filesystem;

// Temporary folders made and registered in one step (the interrupt handler itself is exercised
// by the command-line tests that send SIGINT and SIGTERM).
TEST(TempDirectories, AreMadeOrTheFailureIsSaid) {
  testing::TempDir dir;
  std::error_code ec;
  const std::string nested = dir.File("a/b/c");
  const int id = CreateTempDirectory(nested, &ec);
  EXPECT_GE(id, 0) << ec.message();
  EXPECT_TRUE(fs::is_directory(nested));
  UnregisterTempPath(id);
  EXPECT_GE(CreateTempDirectory(nested, &ec), 0) << "an existing folder is fine";
  std::ofstream(dir.File("file")) << "x";
  EXPECT_EQ(CreateTempDirectory(dir.File("file/sub"), &ec), -1);
  EXPECT_TRUE(ec) << "the error is said";

  std::string pattern = dir.File("view-XXXXXX");
  const int made = MakeTempDirectory(&pattern);
  EXPECT_GE(made, 0);
  EXPECT_EQ(pattern.find("XXXXXX"), std::string::npos) << pattern;
  EXPECT_TRUE(fs::is_directory(pattern));
  UnregisterTempPath(made);
  std::string missing = dir.File("no/such/view-XXXXXX");
  EXPECT_EQ(MakeTempDirectory(&missing), -1);
}

}  // namespace
}  // namespace candi

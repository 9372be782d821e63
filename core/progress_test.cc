#include "core/progress.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace candi {
namespace {

TEST(ConsoleProgress, PlainLinesAreThrottledAndFinishOnce) {
  std::vector<std::string> lines;
  ConsoleProgressOptions options;
  options.force_tty = 0;
  options.line_interval_s = 3600;  // only the first update and the final line
  {
    ConsoleProgress progress("read", options, [&](const std::string& s) { lines.push_back(s); });
    for (int i = 1; i <= 100; ++i) progress.Update(i, 100);
    progress.Finish();
    progress.Finish();
  }
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[0].find("read:"), std::string::npos);
  EXPECT_NE(lines[0].find("1.0%"), std::string::npos) << lines[0];
  EXPECT_NE(lines[1].find("100.0%"), std::string::npos) << lines[1];
  EXPECT_NE(lines[1].find("done"), std::string::npos);
  EXPECT_EQ(lines[1].find('['), std::string::npos) << "no bar off a terminal";
  // A finish that repeats the last printed state prints nothing more.
  lines.clear();
  ConsoleProgress once("one", options, [&](const std::string& s) { lines.push_back(s); });
  once.Update(10, 10);
  once.Finish();
  EXPECT_EQ(lines.size(), 1u);
}

TEST(ConsoleProgress, TerminalDrawsABarAndUnknownTotalsCount) {
  std::vector<std::string> lines;
  ConsoleProgressOptions options;
  options.force_tty = 1;
  ConsoleProgress bar("x", options, [&](const std::string& s) { lines.push_back(s); });
  bar.Update(5, 10);
  EXPECT_NE(lines.back().find("[###############"), std::string::npos) << lines.back();
  lines.clear();
  ConsoleProgress open("y", options, [&](const std::string& s) { lines.push_back(s); });
  open.Update(7, 0);
  EXPECT_EQ(lines.back().find('%'), std::string::npos);
  EXPECT_NE(lines.back().find("7 points"), std::string::npos);
}

TEST(StagedProgress, ABarAStageEachFinishedWhenTheNextStarts) {
  std::vector<std::string> lines;
  ConsoleProgressOptions options;
  options.force_tty = 0;
  options.line_interval_s = 3600;
  {
    StagedProgress stages("write x.copc.laz", options,
                          [&](const std::string& s) { lines.push_back(s); });
    const StageProgressCallback report = stages.Callback();
    report("octree", 10, 100);
    report("octree", 100, 100);
    report("chunks", 50, 100);
    report("chunks", 100, 100);
  }  // the destructor finishes the last stage
  ASSERT_EQ(lines.size(), 4u);
  EXPECT_EQ(lines[0].rfind("write x.copc.laz: octree:", 0), 0u) << lines[0];
  EXPECT_NE(lines[1].find("100.0%"), std::string::npos) << lines[1];
  EXPECT_NE(lines[1].find("done"), std::string::npos) << "octree finished as chunks start";
  EXPECT_EQ(lines[2].rfind("write x.copc.laz: chunks:", 0), 0u) << lines[2];
  EXPECT_NE(lines[2].find("50.0%"), std::string::npos) << lines[2];
  EXPECT_NE(lines[3].find("done"), std::string::npos) << lines[3];
}

TEST(ConsoleProgressOptions, DefaultsPassAndNegativesFail) {
  EXPECT_NO_THROW(ConsoleProgressOptions{}.Check());
  ConsoleProgressOptions bad;
  bad.line_interval_s = -1;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace candi

#include "core/task_progress.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>
#include <vector>

namespace candi {
namespace {

// Plain lines, only a task's first update and its final line.
ConsoleProgressOptions FirstAndLast() {
  ConsoleProgressOptions o;
  o.force_tty = 0;
  o.line_interval_s = 3600;
  return o;
}

TEST(ConsoleTasks, ABarATaskLabelledAndCountedAsTheTaskSays) {
  std::vector<std::string> lines;
  ConsoleTasks tasks(FirstAndLast(), [&](const std::string& s) { lines.push_back(s); });
  const TaskProgress callbacks = tasks.Callbacks();
  {
    ProgressTask task(callbacks, "register 3 scans", "steps");
    task.callback()(1, 4);
    task.callback()(4, 4);
  }  // finished here, before the next task begins
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].rfind("register 3 scans:", 0), 0u) << lines[0];
  EXPECT_NE(lines[0].find(" 1 steps"), std::string::npos) << lines[0];
  EXPECT_NE(lines[1].find("done"), std::string::npos) << lines[1];
  // A task that fails is finished as the exception leaves it; one that reports nothing still
  // says it is done, as a ConsoleProgress does.
  lines.clear();
  try {
    ProgressTask task(callbacks, "pack");
    throw std::runtime_error("bad file");
  } catch (const std::runtime_error&) {
  }
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0].rfind("pack: 0 points", 0), 0u) << lines[0];
  EXPECT_NE(lines[0].find("done"), std::string::npos) << lines[0];
}

TEST(ProgressTask, WithoutCallbacksItReportsNowhere) {
  ProgressTask quiet(TaskProgress{}, "quiet");
  EXPECT_FALSE(quiet.callback());
  int finished = 0;
  {
    ProgressTask only_finish(TaskProgress{nullptr, [&] { ++finished; }}, "x");
    EXPECT_FALSE(only_finish.callback());
  }
  EXPECT_EQ(finished, 1);
}

}  // namespace
}  // namespace candi

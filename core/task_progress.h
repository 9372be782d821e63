// Progress of tasks whose label only the library knows when they start: how many scans the E57
// files hold, how many points a preview packs. The library calls start(label, unit) as a task
// begins and reports through the callback start returns (core/progress.h), then finish() once
// the task is over, done or failed; apps pass a ConsoleTasks, which draws a ConsoleProgress bar a
// task on stderr. One task at a time.
#pragma once

#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include "core/progress.h"

namespace candi {

struct TaskProgress {
  // A task begins: its label ("register 4 scans") and what it counts ("steps"); returns where
  // its progress goes (may be null). Null: no report.
  std::function<ProgressCallback(const std::string& label, const std::string& unit)> start;
  std::function<void()> finish;  // the task begun last is over; null: nothing to do
};

// The library's side of one task: begun on construction, finished on destruction (an exception
// that leaves the task finishes it too).
class ProgressTask {
 public:
  ProgressTask(const TaskProgress& tasks, const std::string& label,
               const std::string& unit = "points");
  ~ProgressTask();
  ProgressTask(const ProgressTask&) = delete;
  ProgressTask& operator=(const ProgressTask&) = delete;

  // Where the task's progress goes (null when `tasks` has no start, or start gave none).
  const ProgressCallback& callback() const { return callback_; }

 private:
  std::function<void()> finish_;
  ProgressCallback callback_;
};

// Tasks drawn as ConsoleProgress bars: one a task, labelled and counted as the task says,
// finished when the task finishes (or the next begins). Thread-safe for one task at a time, on
// any thread; the destructor finishes the last.
class ConsoleTasks {
 public:
  explicit ConsoleTasks(ConsoleProgressOptions options = {},
                        std::function<void(const std::string&)> sink = nullptr);
  ~ConsoleTasks();
  ConsoleTasks(const ConsoleTasks&) = delete;
  ConsoleTasks& operator=(const ConsoleTasks&) = delete;

  TaskProgress Callbacks();  // callbacks bound to this reporter

 private:
  ProgressCallback Start(const std::string& label, const std::string& unit);
  void Finish();

  ConsoleProgressOptions options_;
  std::function<void(const std::string&)> sink_;
  std::mutex mutex_;
  std::unique_ptr<ConsoleProgress> bar_;
};

}  // namespace candi

#include "core/task_progress.h"

#include <utility>

namespace candi {

ProgressTask::ProgressTask(const TaskProgress& tasks, const std::string& label,
                           const std::string& unit)
    : finish_(tasks.finish) {
  if (tasks.start) callback_ = tasks.start(label, unit);
}

ProgressTask::~ProgressTask() {
  try {
    if (finish_) finish_();
  } catch (...) {
  }
}

ConsoleTasks::ConsoleTasks(ConsoleProgressOptions options,
                           std::function<void(const std::string&)> sink)
    : options_(std::move(options)), sink_(std::move(sink)) {
  options_.Check();
}

ConsoleTasks::~ConsoleTasks() {
  try {
    Finish();
  } catch (...) {
  }
}

TaskProgress ConsoleTasks::Callbacks() {
  return {[this](const std::string& label, const std::string& unit) { return Start(label, unit); },
          [this] { Finish(); }};
}

ProgressCallback ConsoleTasks::Start(const std::string& label, const std::string& unit) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (bar_) bar_->Finish();
  ConsoleProgressOptions options = options_;
  options.unit = unit;
  bar_ = std::make_unique<ConsoleProgress>(label, options, sink_);
  return bar_->Callback();
}

void ConsoleTasks::Finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (bar_) bar_->Finish();
}

}  // namespace candi

// Progress reporting for long work.
//
// Libraries report through a ProgressCallback (never print); apps pass a ConsoleProgress, which
// draws a bar on stderr when stderr is a terminal and prints plain lines otherwise (logs, CI).
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>

namespace candi {

// Turns console progress off (-q) or on for the whole process.
void SetConsoleProgressEnabled(bool enabled);

// Called with work done and total (total 0 = unknown). Must be cheap; may be called often.
using ProgressCallback = std::function<void(uint64_t done, uint64_t total)>;
// The same for work in named stages, one after the other (e.g. a COPC file's "octree", then
// "chunks"): done and total count within the stage.
using StageProgressCallback =
    std::function<void(const std::string& stage, uint64_t done, uint64_t total)>;

struct ConsoleProgressOptions {
  double min_interval_s = 0.1;    // minimum seconds between bar redraws on a terminal, >= 0
  double line_interval_s = 5.0;   // minimum seconds between plain lines (not a terminal), >= 0
  int force_tty = -1;             // -1 detect, 0 plain lines, 1 bar (tests)
  std::string unit = "points";    // what is counted, for the message
  void Check() const;
};

// Thread-safe. Writes to stderr (or to `sink` for tests). Finish() prints the final state and
// the elapsed time once; the destructor calls it.
class ConsoleProgress {
 public:
  ConsoleProgress(std::string label, ConsoleProgressOptions options = {},
                  std::function<void(const std::string&)> sink = nullptr);
  ~ConsoleProgress();
  ConsoleProgress(const ConsoleProgress&) = delete;
  ConsoleProgress& operator=(const ConsoleProgress&) = delete;

  void Update(uint64_t done, uint64_t total);
  void Finish();
  ProgressCallback Callback();  // a callback bound to this reporter

 private:
  void Emit(const std::string& text);
  std::string Render(uint64_t done, uint64_t total, bool final) const;

  std::string label_;
  ConsoleProgressOptions options_;
  std::function<void(const std::string&)> sink_;
  bool tty_;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_, last_;
  uint64_t done_ = 0, total_ = 0;
  bool finished_ = false, drawn_ = false;
  uint64_t drawn_done_ = 0;  // `done` of the last line printed
};

// A ConsoleProgress a stage, labelled "<label>: <stage>": a new one starts (the last one
// finished) whenever the stage changes. Thread-safe; the destructor finishes the last.
class StagedProgress {
 public:
  explicit StagedProgress(std::string label, ConsoleProgressOptions options = {},
                          std::function<void(const std::string&)> sink = nullptr);
  void Update(const std::string& stage, uint64_t done, uint64_t total);
  void Finish();
  StageProgressCallback Callback();  // a callback bound to this reporter

 private:
  std::string label_;
  ConsoleProgressOptions options_;
  std::function<void(const std::string&)> sink_;
  std::mutex mutex_;
  std::string stage_;
  std::unique_ptr<ConsoleProgress> bar_;
};

}  // namespace candi

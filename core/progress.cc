#include "core/progress.h"

#include "core/check.h"

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <stdexcept>

namespace candi {

namespace {
std::atomic<bool> g_enabled{true};
}  // namespace

void SetConsoleProgressEnabled(bool enabled) { g_enabled = enabled; }

void ConsoleProgressOptions::Check() const {
  CANDI_CHECK_OPTION_GE(min_interval_s, 0);
  CANDI_CHECK_OPTION_GE(line_interval_s, 0);
}

ConsoleProgress::ConsoleProgress(std::string label, ConsoleProgressOptions options,
                                 std::function<void(const std::string&)> sink)
    : label_(std::move(label)), options_(std::move(options)), sink_(std::move(sink)) {
  options_.Check();
  tty_ = options_.force_tty >= 0 ? options_.force_tty == 1 : isatty(STDERR_FILENO) == 1;
  start_ = last_ = std::chrono::steady_clock::now();
}

ConsoleProgress::~ConsoleProgress() {
  try {
    Finish();
  } catch (...) {
  }
}

ProgressCallback ConsoleProgress::Callback() {
  return [this](uint64_t done, uint64_t total) { Update(done, total); };
}

std::string ConsoleProgress::Render(uint64_t done, uint64_t total, bool final) const {
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const double rate = elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
  char tail[128];
  std::snprintf(tail, sizeof(tail), " %llu %s, %.1f s, %.3g %s/s",
                static_cast<unsigned long long>(done), options_.unit.c_str(), elapsed, rate,
                options_.unit.c_str());
  std::string text = label_ + ":";
  if (total > 0) {
    const double fraction = std::min(1.0, static_cast<double>(done) / static_cast<double>(total));
    char pct[16];
    std::snprintf(pct, sizeof(pct), " %5.1f%%", 100.0 * fraction);
    if (tty_) {
      constexpr int kWidth = 30;
      const int filled = static_cast<int>(fraction * kWidth);
      text += " [" + std::string(filled, '#') + std::string(kWidth - filled, '.') + "]";
    }
    text += pct;
  }
  text += tail;
  if (!final && total > 0 && done > 0 && done < total && elapsed >= 1) {
    char left[48];
    std::snprintf(left, sizeof(left), ", ~%.0f s left", elapsed * static_cast<double>(total - done) / done);
    text += left;
  }
  if (final) text += " done";
  return text;
}

void ConsoleProgress::Emit(const std::string& text) {
  if (sink_) {
    sink_(text);
    return;
  }
  if (!g_enabled) return;
  if (tty_) {
    std::fprintf(stderr, "\r%s\x1b[K", text.c_str());
  } else {
    std::fprintf(stderr, "%s\n", text.c_str());
  }
  std::fflush(stderr);
}

void ConsoleProgress::Update(uint64_t done, uint64_t total) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  done_ = done;
  total_ = total;
  const auto now = std::chrono::steady_clock::now();
  const double since = std::chrono::duration<double>(now - last_).count();
  const double interval = tty_ ? options_.min_interval_s : options_.line_interval_s;
  if (drawn_ && since < interval) return;
  last_ = now;
  drawn_ = true;
  drawn_done_ = done;
  Emit(Render(done, total, false));
}

void ConsoleProgress::Finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (finished_) return;
  finished_ = true;
  // Off a terminal, a final line that would repeat the last one is left out.
  if (tty_ || !drawn_ || drawn_done_ != done_) Emit(Render(done_, total_, true));
  if (tty_ && !sink_ && g_enabled) {
    std::fprintf(stderr, "\n");
    std::fflush(stderr);
  }
}

StagedProgress::StagedProgress(std::string label, ConsoleProgressOptions options,
                               std::function<void(const std::string&)> sink)
    : label_(std::move(label)), options_(std::move(options)), sink_(std::move(sink)) {
  options_.Check();
}

void StagedProgress::Update(const std::string& stage, uint64_t done, uint64_t total) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!bar_ || stage != stage_) {
    if (bar_) bar_->Finish();
    bar_ = std::make_unique<ConsoleProgress>(label_ + ": " + stage, options_, sink_);
    stage_ = stage;
  }
  bar_->Update(done, total);
}

void StagedProgress::Finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (bar_) bar_->Finish();
}

StageProgressCallback StagedProgress::Callback() {
  return [this](const std::string& stage, uint64_t done, uint64_t total) {
    Update(stage, done, total);
  };
}

}  // namespace candi

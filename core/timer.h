// Wall-clock time for reports: the seconds a stage took, printed or kept in a timings file (never
// in an output that must be the same bytes on every run). Not thread-safe (one owner).
#pragma once

#include <sys/resource.h>

#include <chrono>

namespace candi {

class Stopwatch {
 public:
  Stopwatch() : start_(std::chrono::steady_clock::now()), lap_(start_) {}
  // Seconds since construction (or the last Restart).
  double Seconds() const { return Since(start_); }
  // Seconds since the previous Lap (or construction): the stages of a run one after another.
  double Lap() {
    const auto now = std::chrono::steady_clock::now();
    const double s = std::chrono::duration<double>(now - lap_).count();
    lap_ = now;
    return s;
  }
  void Restart() { start_ = lap_ = std::chrono::steady_clock::now(); }

 private:
  static double Since(std::chrono::steady_clock::time_point t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  }
  std::chrono::steady_clock::time_point start_, lap_;
};

// The peak resident memory of this process so far, MB (for reports, beside the seconds).
inline double PeakMemoryMb() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss / 1024.0;
}

}  // namespace candi

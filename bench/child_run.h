// Benchmarks that time candi (or a peer tool) as a child process: its wall time, CPU time and
// peak resident memory (wait4) are its own, not the benchmark's.
#pragma once

#include <string>
#include <vector>

namespace candi::bench {

struct ChildRun {
  int code = -1;
  double seconds = 0;
  double peak_mb = 0;  // the largest resident set of the child or any of its descendants
  double cpu_seconds = 0;  // user + system CPU of the child and its descendants
  std::string out;     // stdout
};

// Runs argv (PATH lookup), capturing stdout; stderr passes through. An interrupt of candi stops it.
ChildRun RunChild(const std::vector<std::string>& argv);

// This executable's path (/proc/self/exe).
std::string SelfPath();

}  // namespace candi::bench

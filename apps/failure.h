// How `candi` reports a failure: the line it prints on stderr and the exit code (cli.h's
// ExitCode). main() uses it for every exception that reaches it; the MPI commands (render, sfm) use it
// to send a failed rank's report to rank 0 before any process exits.
#pragma once

#include <exception>
#include <stdexcept>
#include <string>
#include <utility>

#include "pipeline/render_ranks.h"

namespace candi::apps {

struct FailureReport {
  int exit_code = 0;   // kUsage, kBadInput or kInternal
  std::string text;    // "candi: error: ...", without a final newline
};

// The report of an exception: InputError -> 2, std::invalid_argument -> 1, anything else -> 3.
FailureReport DescribeFailure(std::exception_ptr failure);
// The same as the MPI split wants it (render/mpi/archive_ranks.h's FailureDescriber): the exit
// code and the line.
std::pair<int, std::string> DescribeFailureForMpi(std::exception_ptr failure);

// How a command under mpirun reports (pipeline/render_ranks.h): a failure as DescribeFailureForMpi
// gives it, and on rank 0, before any process exits, every failed rank's report and then that
// every rank stopped, with `outcome` ("no image written").
pipeline::RanksReporting RankReporting(const std::string& outcome);

// A failure whose report is on stderr already (an MPI rank's, printed by rank 0 for every rank):
// main() returns exit_code() and prints nothing more.
class ReportedFailure : public std::runtime_error {
 public:
  explicit ReportedFailure(int exit_code) : std::runtime_error("reported"), exit_code_(exit_code) {}
  int exit_code() const { return exit_code_; }

 private:
  int exit_code_;
};

}  // namespace candi::apps

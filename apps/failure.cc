#include "apps/failure.h"

#include <cstdio>
#include <new>

#include "apps/cli.h"
#include "core/check.h"

namespace candi::apps {

FailureReport DescribeFailure(std::exception_ptr failure) {
  try {
    std::rethrow_exception(failure);
  } catch (const InputError& e) {
    return {kBadInput, std::string("candi: error: ") + e.what()};
  } catch (const std::invalid_argument& e) {
    return {kUsage, std::string("candi: invalid option value: ") + e.what()};
  } catch (const InternalError& e) {
    return {kInternal, std::string("candi: internal error (please report): ") + e.what()};
  } catch (const std::bad_alloc&) {
    return {kInternal, "candi: internal error: out of memory"};
  } catch (const std::exception& e) {
    return {kInternal, std::string("candi: internal error: ") + e.what()};
  } catch (...) {
    return {kInternal, "candi: internal error: an unknown exception"};
  }
}

std::pair<int, std::string> DescribeFailureForMpi(std::exception_ptr failure) {
  const FailureReport report = DescribeFailure(failure);
  return {report.exit_code, report.text};
}

pipeline::RanksReporting RankReporting(const std::string& outcome) {
  return {DescribeFailureForMpi, [outcome](const std::vector<render::mpi::Session::Failure>& failures, int ranks) {
            for (const auto& f : failures) {
              const size_t skip = f.message.rfind("candi: ", 0) == 0 ? 7 : 0;  // the report's own prefix
              std::fprintf(stderr, "candi: MPI rank %d of %d failed: %s\n", f.rank, ranks, f.message.c_str() + skip);
            }
            std::fprintf(stderr, "candi: every rank stopped because %s failed; %s\n",
                         failures.size() == 1 && failures[0].rank != 0 ? "another rank" : "a rank", outcome.c_str());
            std::fflush(stderr);
          }};
}

}  // namespace candi::apps

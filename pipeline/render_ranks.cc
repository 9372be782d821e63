#include "pipeline/render_ranks.h"

#include <exception>
#include <memory>
#include <utility>

#include "core/progress.h"
#include "render/archive.h"

namespace candi::pipeline {

std::vector<render::mpi::Session::Failure> GatherRankFailures(const render::mpi::Session& session,
                                                              std::exception_ptr failure,
                                                              const RanksReporting& reporting) {
  const std::pair<int, std::string> mine = failure ? reporting.describe(failure) : std::pair<int, std::string>();
  std::vector<render::mpi::Session::Failure> failures = session.GatherFailures(mine.first, mine.second);
  if (!failures.empty()) {
    if (session.rank() == 0 && reporting.failed) reporting.failed(failures, session.size());
    session.Barrier();
  }
  return failures;
}

RanksRender RenderArchiveOnRanks(const RenderOptions& options, const std::string& archive_dir,
                                 const RanksReporting& reporting) {
  std::unique_ptr<render::mpi::Session> session;
  if (render::mpi::LaunchedByMpi()) session = std::make_unique<render::mpi::Session>();
  const int rank = session ? session->rank() : 0, ranks = session ? session->size() : 1;
  if (rank != 0) SetConsoleProgressEnabled(false);  // one bar, rank 0's
  RanksRender out;
  out.root = rank == 0;
  std::exception_ptr failure;
  try {
    const render::Archive archive(archive_dir);
    out.image = RenderArchiveEnsembles(options, archive, rank, ranks);
  } catch (...) {
    failure = std::current_exception();
  }
  if (!session) {
    if (failure) std::rethrow_exception(failure);
    return out;
  }
  out.failures = GatherRankFailures(*session, failure, reporting);
  if (!out.failures.empty()) return out;
  session->ReduceToRoot(&out.image.result);
  return out;
}

}  // namespace candi::pipeline

#include "pipeline/dense_ranks.h"

#include <exception>
#include <utility>

#include "core/progress.h"

namespace candi::pipeline {

RanksDense DenseStereoOnRanks(const DenseOptions& options, const std::string& workspace,
                              const RanksReporting& reporting,
                              const std::function<void(const PointCloud& cell)>& cells_out) {
  RanksDense out;
  if (!render::mpi::LaunchedByMpi()) {
    DenseRankShare one;
    one.cells_out = cells_out;
    out.dense = DenseStereo(options, workspace, one);
    return out;
  }
  const render::mpi::Session session;
  const int rank = session.rank(), ranks = session.size();
  out.root = rank == 0;
  if (rank != 0) SetConsoleProgressEnabled(false);  // one report, rank 0's
  std::exception_ptr failure;
  try {
    DenseRankShare share;
    share.rank = rank;
    share.ranks = ranks;
    share.all_gather = [&session](const std::string& mine) { return session.AllGather(mine); };
    share.cells_out = cells_out;
    out.dense = DenseStereo(options, workspace, share);
  } catch (...) {
    failure = std::current_exception();
  }
  out.failures = GatherRankFailures(session, failure, reporting);
  if (out.failures.empty()) session.Barrier();
  return out;
}

}  // namespace candi::pipeline

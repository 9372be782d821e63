// `candi render ARCHIVE`, under mpirun as one of its ranks (render/mpi/): every rank draws its
// share of the ensembles (RenderArchiveEnsembles), the ranks agree that all succeeded, and the
// sums are added on rank 0, which alone holds the whole image; without mpirun, the whole image in
// this one process. The image is the same bits either way.
//
// A failed rank makes every rank fail, with no image: rank 0 is given every rank's failure before
// any rank returns, since mpirun ends the job when the first process exits non-zero and a report
// another rank had yet to print would be lost. Only rank 0 reports progress. Failures without
// mpirun: those of render::Archive and RenderArchiveEnsembles, thrown. Library candi_pipeline_mpi
// (MPI), linked only by the command line.
#pragma once

#include <exception>
#include <functional>
#include <string>
#include <vector>

#include "pipeline/render.h"
#include "render/mpi/archive_ranks.h"
#include "render/mpi/mpi_session.h"

namespace candi::pipeline {

struct RanksReporting {
  // A failure as its exit code and one line (apps/failure.h's DescribeFailure).
  render::mpi::FailureDescriber describe;
  // Rank 0, when any rank failed: every failed rank's report (rank order) and the number of
  // ranks, called before any rank returns.
  std::function<void(const std::vector<render::mpi::Session::Failure>& failures, int ranks)> failed;
};

// Ends a run on every rank: each rank's failure (none: a null `failure`) goes to every rank; rank
// 0 gives them to `reporting.failed` before any rank returns (the barrier holds the others).
std::vector<render::mpi::Session::Failure> GatherRankFailures(const render::mpi::Session& session,
                                                              std::exception_ptr failure,
                                                              const RanksReporting& reporting);

struct RanksRender {
  bool root = true;  // rank 0, or no mpirun: `image` holds the sums of every rank
  RenderedImage image;
  // Under mpirun: the ranks' failures, in rank order (given to `failed` on rank 0); when any,
  // there is no image.
  std::vector<render::mpi::Session::Failure> failures;
};

// The archive in `archive_dir` rendered with `options` (options.alpha empty: an archive holds
// one copy per point).
RanksRender RenderArchiveOnRanks(const RenderOptions& options, const std::string& archive_dir,
                                 const RanksReporting& reporting);

}  // namespace candi::pipeline

// `candi dense` under mpirun: photo r's depth map and filter go to rank r mod ranks, fusion cell
// t to rank t mod ranks, over one workspace every rank sees (a shared file system across
// machines); the stages end together (photogrammetry/mvs/dense_stream.h), and rank 0 gathers the
// cells into the cloud, the same bytes as one process.
//
// A failed rank makes every rank fail: rank 0 is given every rank's failure before any rank
// returns (as pipeline/render_ranks.h). Without mpirun: DenseStereo in this process.
// Library candi_pipeline_mpi (MPI), linked only by the command line.
#pragma once

#include <string>
#include <vector>

#include "pipeline/photogrammetry.h"
#include "pipeline/render_ranks.h"

namespace candi::pipeline {

struct RanksDense {
  bool root = true;  // rank 0, or no mpirun: `dense` is the run's (the other ranks' have no points)
  DenseCloud dense;
  std::vector<render::mpi::Session::Failure> failures;  // under mpirun, in rank order
};

// `cells_out`: as DenseRankShare's (called on rank 0 only).
RanksDense DenseStereoOnRanks(const DenseOptions& options, const std::string& workspace,
                              const RanksReporting& reporting,
                              const std::function<void(const PointCloud& cell)>& cells_out = nullptr);

}  // namespace candi::pipeline

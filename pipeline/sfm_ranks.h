// `candi sfm` under mpirun: the chunk mappers of a campaign mapped in chunks (--targets) go to the
// ranks. Rank 0 runs everything else (extraction, matching, the ties, the merge) and hands the
// mapper jobs out when it reaches them: chunk k to rank k mod ranks, each rank running its share
// `--chunk-parallel` at once. A chunk's mapper is the same command on any rank, so the model is
// the same bytes on 1 or N ranks. The workspace must be one folder every rank sees (a shared file
// system across machines). Without --targets there is one mapper, and the other ranks wait.
//
// A failed rank makes every rank fail: rank 0 is given every rank's failure before any rank
// returns (as pipeline/render_ranks.h). Without mpirun: StructureFromMotion in this process.
// Library candi_pipeline_mpi (MPI), linked only by the command line.
#pragma once

#include <string>
#include <vector>

#include "pipeline/photogrammetry.h"
#include "pipeline/render_ranks.h"

namespace candi::pipeline {

struct RanksSfm {
  bool root = true;                    // rank 0, or no mpirun: `summary` is the run's
  photogrammetry::SfmSummary summary;
  std::vector<render::mpi::Session::Failure> failures;  // under mpirun, in rank order; when any, no summary
};

RanksSfm StructureFromMotionOnRanks(const photogrammetry::SfmOptions& options, const std::string& images,
                                    const std::string& workspace, const RanksReporting& reporting);

// The jobs as rank 0 broadcasts them, and back (exposed for tests).
std::string ChunkJobsToText(const std::vector<photogrammetry::ChunkMapperJob>& jobs);
std::vector<photogrammetry::ChunkMapperJob> ChunkJobsFromText(const std::string& text);

}  // namespace candi::pipeline

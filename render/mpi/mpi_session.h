// MPI for distributed SPBR: each rank draws a share of the L ensembles, and the exact integer
// sums are added on rank 0 (one MPI_Reduce per frame), so the image is bit-identical to the
// one-process render. The header speaks no MPI types: only this library links MPI.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "render/spbr.h"

namespace candi::render::mpi {

// True when this process was started by mpirun/mpiexec (OMPI_COMM_WORLD_SIZE, PMI_SIZE or
// PMIX_RANK set), so a plain `candi render` never initializes MPI.
bool LaunchedByMpi();

// MPI_Init_thread on construction, MPI_Finalize on destruction. One per process. `serialized`:
// MPI may be called from any one thread at a time (the viewer's render thread), not only from
// the main one.
class Session {
 public:
  explicit Session(bool serialized = false);
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  // Collective: every rank passes its failure (exit_code 0 = none); every rank gets the failures
  // of all ranks, in rank order (empty when none failed). So rank 0 can report a failed rank's
  // reason itself, before any process exits (mpirun ends the whole job when the first process
  // exits non-zero, and a message still to be printed by another rank would be lost).
  struct Failure {
    int rank = 0;
    int exit_code = 0;
    std::string message;
  };
  std::vector<Failure> GatherFailures(int exit_code, const std::string& message) const;
  // Collective: every rank's bytes to every rank, in rank order (under 1 GiB in all).
  std::vector<std::string> AllGather(const std::string& mine) const;
  // Collective: rank 0's bytes to every rank.
  void Broadcast(std::string* bytes) const;
  // Collective: returns when every rank has called it.
  void Barrier() const;
  // Collective: adds the ranks' sums, grey histograms and copy counts onto rank 0's `result`.
  // Throws InternalError when the ranks' image sizes differ.
  void ReduceToRoot(SpbrResult* result) const;

 private:
  int rank_ = 0, size_ = 1;
};

}  // namespace candi::render::mpi

// MPI for distributed SPBR: each rank draws a share of the L ensembles, and the exact integer
// sums are added on rank 0 (one MPI_Reduce per frame), so the image is bit-identical to the
// one-process render. The header speaks no MPI types: only this library links MPI.
#pragma once

#include <memory>

#include "render/spbr.h"

namespace candi::render::mpi {

// True when this process was started by mpirun/mpiexec (OMPI_COMM_WORLD_SIZE, PMI_SIZE or
// PMIX_RANK set), so a plain `candi render` never initializes MPI.
bool LaunchedByMpi();

// Ensembles [*begin, *end) of `rank` among `size` ranks: contiguous shares of L, sizes differing
// by at most one (a rank may get none when size > L).
void EnsembleShare(int repeat_level, int rank, int size, int* begin, int* end);

// MPI_Init_thread on construction, MPI_Finalize on destruction. One per process.
class Session {
 public:
  Session();
  ~Session();
  Session(const Session&) = delete;
  Session& operator=(const Session&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  // Collective: true when every rank passes ok = true (so a failed rank stops all, no hang).
  bool AllOk(bool ok) const;
  // Collective: adds the ranks' sums, grey histograms and copy counts onto rank 0's `result`.
  // Throws InternalError when the ranks' image sizes differ.
  void ReduceToRoot(SpbrResult* result) const;

 private:
  int rank_ = 0, size_ = 1;
};

}  // namespace candi::render::mpi

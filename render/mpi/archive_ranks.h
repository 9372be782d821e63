// An archive's images drawn by several MPI ranks on request (the viewer under mpirun): rank 0
// broadcasts each step's request (camera, ensembles, settings) as text, every rank draws its share
// of the ensembles, and the sums are added on rank 0 exactly as `candi render` does. A rank's
// failure reaches every rank (rank 0 reports it); the other ranks go on serving.
#pragma once

#include <exception>
#include <functional>
#include <string>
#include <utility>

#include "render/archive.h"
#include "render/archive_render.h"
#include "render/camera.h"
#include "render/mpi/mpi_session.h"
#include "render/spbr.h"

namespace candi::render::mpi {

// How a failure is reported: its exit code and one line (apps/failure.h's DescribeFailure).
using FailureDescriber = std::function<std::pair<int, std::string>(std::exception_ptr)>;

// A step's request: the camera (the archive's frame), ensembles [begin, end), L, seed, point size,
// layer shares, clipping, verification. Doubles travel exactly (17 digits).
std::string EncodeArchiveRequest(const ArchiveRenderOptions& options, const Camera& local_camera);

// Collective: this rank's share of the request's ensembles drawn from `archive` with `threads`,
// summed onto rank 0 (its result; the others' are partial). Throws InputError on every rank when
// any rank failed, naming the first failed rank and its message.
SpbrResult RenderRequestShare(const Session& session, const Archive& archive, const std::string& request, int threads,
                              const FailureDescriber& describe);

// Ranks other than 0: the archive rank 0 broadcasts, then its requests until "stop".
void ServeArchiveRequests(const Session& session, int threads, const FailureDescriber& describe);

// What rank 0 broadcasts to end ServeArchiveRequests.
inline constexpr const char* kStopRequest = "stop";

}  // namespace candi::render::mpi

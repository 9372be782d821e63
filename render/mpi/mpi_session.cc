#include "render/mpi/mpi_session.h"

#include <mpi.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/check.h"

namespace candi::render::mpi {

bool LaunchedByMpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"}) {
    if (std::getenv(name) != nullptr) return true;
  }
  return false;
}

namespace {
void Check(int code, const char* what) {
  if (code != MPI_SUCCESS) {
    char text[MPI_MAX_ERROR_STRING];
    int length = 0;
    MPI_Error_string(code, text, &length);
    throw InternalError(std::string(what) + " failed: " + std::string(text, length));
  }
}
}  // namespace

Session::Session(bool serialized) {
  int provided = 0;
  const int wanted = serialized ? MPI_THREAD_SERIALIZED : MPI_THREAD_FUNNELED;
  Check(MPI_Init_thread(nullptr, nullptr, wanted, &provided), "MPI_Init_thread");
  if (provided < wanted) {
    MPI_Finalize();
    throw InternalError("this MPI library does not let a thread other than the main one call it "
                        "(MPI_THREAD_SERIALIZED)");
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
}

Session::~Session() { MPI_Finalize(); }

std::vector<std::string> Session::AllGather(const std::string& mine) const {
  CANDI_CHECK(mine.size() < (size_t{1} << 30)) << "all-gather of " << mine.size() << " bytes";
  const int length = static_cast<int>(mine.size());
  std::vector<int> lengths(size_), offsets(size_);
  Check(MPI_Allgather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, MPI_COMM_WORLD), "MPI_Allgather");
  int64_t total = 0;
  for (int r = 0; r < size_; ++r) {
    offsets[r] = static_cast<int>(total);
    total += lengths[r];
  }
  CANDI_CHECK(total < (int64_t{1} << 31)) << "all-gather of " << total << " bytes";
  std::string all(static_cast<size_t>(total), '\0');
  Check(MPI_Allgatherv(mine.data(), length, MPI_CHAR, all.data(), lengths.data(), offsets.data(), MPI_CHAR,
                       MPI_COMM_WORLD),
        "MPI_Allgatherv");
  std::vector<std::string> out;
  for (int r = 0; r < size_; ++r) out.push_back(all.substr(offsets[r], lengths[r]));
  return out;
}

std::vector<Session::Failure> Session::GatherFailures(int exit_code, const std::string& message) const {
  // "code message" from a rank that failed, "" from one that did not.
  const std::string mine =
      exit_code == 0 ? std::string() : std::to_string(exit_code) + " " + message.substr(0, size_t{1} << 16);
  const std::vector<std::string> all = AllGather(mine);
  std::vector<Failure> failures;
  for (int r = 0; r < size_; ++r) {
    if (all[r].empty()) continue;
    const size_t space = all[r].find(' ');
    failures.push_back({r, std::stoi(all[r].substr(0, space)), all[r].substr(space + 1)});
  }
  return failures;
}

void Session::Broadcast(std::string* bytes) const {
  uint64_t n = bytes->size();
  Check(MPI_Bcast(&n, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD), "MPI_Bcast");
  CANDI_CHECK(n < (uint64_t{1} << 30)) << "broadcast of " << n << " bytes";
  bytes->resize(static_cast<size_t>(n));
  Check(MPI_Bcast(bytes->data(), static_cast<int>(n), MPI_CHAR, 0, MPI_COMM_WORLD), "MPI_Bcast");
}

void Session::Barrier() const { Check(MPI_Barrier(MPI_COMM_WORLD), "MPI_Barrier"); }

void Session::ReduceToRoot(SpbrResult* result) const {
  // The image size first, so a mismatch is an error, not a garbled reduction.
  const uint64_t n = result->sums.sums.size();
  uint64_t lo = n, hi = n;
  Check(MPI_Allreduce(&n, &lo, 1, MPI_UINT64_T, MPI_MIN, MPI_COMM_WORLD), "MPI_Allreduce");
  Check(MPI_Allreduce(&n, &hi, 1, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
  CANDI_CHECK(lo == hi) << "ranks rendered different image sizes";
  const bool root = rank_ == 0;
  // In slices of at most 2^30 values (MPI counts are int).
  uint32_t* sums = result->sums.sums.data();
  for (uint64_t at = 0; at < n; at += uint64_t{1} << 30) {
    const int count = static_cast<int>(std::min<uint64_t>(uint64_t{1} << 30, n - at));
    Check(MPI_Reduce(root ? MPI_IN_PLACE : sums + at, root ? sums + at : nullptr, count, MPI_UINT32_T, MPI_SUM, 0,
                     MPI_COMM_WORLD),
          "MPI_Reduce");
  }
  uint64_t* grey = result->first_ensemble_grey.data();
  Check(MPI_Reduce(root ? MPI_IN_PLACE : grey, root ? grey : nullptr, 256, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD),
        "MPI_Reduce");
  Check(MPI_Reduce(root ? MPI_IN_PLACE : &result->copies, root ? &result->copies : nullptr, 1, MPI_UINT64_T,
                   MPI_SUM, 0, MPI_COMM_WORLD),
        "MPI_Reduce");
  double ms = result->milliseconds, max_ms = 0;
  Check(MPI_Reduce(&ms, &max_ms, 1, MPI_DOUBLE, MPI_MAX, 0, MPI_COMM_WORLD), "MPI_Reduce");
  if (root) result->milliseconds = max_ms;
}

}  // namespace candi::render::mpi

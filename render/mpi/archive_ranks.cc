#include "render/mpi/archive_ranks.h"

#include <nlohmann/json.hpp>

#include "core/check.h"
#include "core/progress.h"
#include "render/view_json.h"

namespace candi::render::mpi {

std::string EncodeArchiveRequest(const ArchiveRenderOptions& o, const Camera& local) {
  const nlohmann::json j = {
      {"camera", nlohmann::json::parse(ViewToJson(local))},
      {"repeat_level", o.spbr.repeat_level},
      {"seed", o.spbr.seed},
      {"point_size", o.spbr.point_size},
      {"opaque", o.spbr.opaque},
      {"begin", o.ensemble_begin},
      {"end", o.ensemble_end},
      {"layers", o.layer_fraction},
      {"clip", ClipPlaneArrays(o.clip)},  // doubles travel exactly (17 digits)
      {"verify", o.verify},
      {"sample", o.sample}};
  return j.dump();
}

SpbrResult RenderRequestShare(const Session& session, const Archive& archive, const std::string& request, int threads,
                              const FailureDescriber& describe) {
  SpbrResult result;
  std::exception_ptr failure;
  try {
    const nlohmann::json j = nlohmann::json::parse(request);
    const Camera camera = ParseView(j.at("camera").dump(), "request");
    ArchiveRenderOptions o;
    o.spbr.repeat_level = j.at("repeat_level").get<int>();
    o.spbr.seed = j.at("seed").get<uint64_t>();
    o.spbr.point_size = j.at("point_size").get<double>();
    o.spbr.opaque = j.at("opaque").get<bool>();
    o.layer_fraction = j.at("layers").get<std::vector<double>>();
    for (const auto& p : j.at("clip")) {
      o.clip.planes.push_back({Eigen::Vector3d(p[0].get<double>(), p[1].get<double>(), p[2].get<double>()),
                               Eigen::Vector3d(p[3].get<double>(), p[4].get<double>(), p[5].get<double>())});
    }
    o.verify = j.at("verify").get<bool>();
    o.sample = j.at("sample").get<double>();
    o.threads = threads;
    const int begin = j.at("begin").get<int>(), end = j.at("end").get<int>();
    int b = 0, e = 0;
    EnsembleShare(end - begin, session.rank(), session.size(), &b, &e);
    o.ensemble_begin = begin + b;
    o.ensemble_end = begin + e;
    result.sums = Accumulator(camera.width, camera.height);
    if (e > b) result = RenderArchive(o, camera, archive);
  } catch (...) {
    failure = std::current_exception();
  }
  const std::pair<int, std::string> mine = failure ? describe(failure) : std::pair<int, std::string>{0, ""};
  const auto failures = session.GatherFailures(mine.first, mine.second);
  if (!failures.empty()) {
    throw InputError("MPI rank " + std::to_string(failures.front().rank) + " of " + std::to_string(session.size()) +
                     " failed: " + failures.front().message);
  }
  session.ReduceToRoot(&result);
  return result;
}

void ServeArchiveRequests(const Session& session, int threads, const FailureDescriber& describe) {
  SetConsoleProgressEnabled(false);
  std::string dir;
  session.Broadcast(&dir);
  const Archive archive(dir);
  for (;;) {
    std::string request;
    session.Broadcast(&request);
    if (request == kStopRequest) return;
    try {
      RenderRequestShare(session, archive, request, threads, describe);
    } catch (const InputError&) {  // reported by rank 0
    }
  }
}

}  // namespace candi::render::mpi

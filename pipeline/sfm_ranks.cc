#include "pipeline/sfm_ranks.h"

#include <exception>
#include <memory>
#include <nlohmann/json.hpp>
#include <utility>

#include "core/check.h"
#include "core/progress.h"

namespace candi::pipeline {

namespace pg = candi::photogrammetry;
using nlohmann::json;

std::string ChunkJobsToText(const std::vector<pg::ChunkMapperJob>& jobs) {
  json a = json::array();
  for (const pg::ChunkMapperJob& j : jobs) a.push_back({{"chunk", j.chunk}, {"argv", j.argv}, {"log", j.log}});
  return a.dump();
}

std::vector<pg::ChunkMapperJob> ChunkJobsFromText(const std::string& text) {
  std::vector<pg::ChunkMapperJob> jobs;
  for (const json& j : json::parse(text)) {
    jobs.push_back({j.at("chunk").get<std::string>(), j.at("argv").get<std::vector<std::string>>(),
                    j.at("log").get<std::string>()});
  }
  return jobs;
}

namespace {

// A rank's errors for its share of the jobs as one text (a JSON object, job index to error; "" = none).
std::string ErrorsText(const std::vector<std::string>& errors) {
  json a = json::object();
  for (size_t k = 0; k < errors.size(); ++k)
    if (!errors[k].empty()) a[std::to_string(k)] = errors[k];
  return a.empty() ? std::string() : a.dump();
}

// Runs this rank's share (job k on rank k mod ranks) and gathers every rank's errors.
std::vector<std::string> RunShare(const render::mpi::Session& session, const std::vector<pg::ChunkMapperJob>& jobs,
                                  int parallel) {
  const int rank = session.rank(), ranks = session.size();
  const auto ours = [&](size_t k) { return static_cast<int>(k % ranks) == rank; };
  std::vector<std::string> mine(jobs.size());
  try {
    mine = pg::RunChunkMappers(jobs, parallel, ours, "rank " + std::to_string(rank) + " of " + std::to_string(ranks));
  } catch (const std::exception& e) {  // every rank must reach the gather below
    for (size_t k = 0; k < jobs.size(); ++k)
      if (ours(k)) mine[k] = "rank " + std::to_string(rank) + ": " + e.what();
  }
  const std::string text = ErrorsText(mine);
  std::vector<std::string> errors(jobs.size());
  for (const auto& f : session.GatherFailures(text.empty() ? 0 : 1, text)) {
    for (const auto& [k, e] : json::parse(f.message).items()) errors.at(std::stoul(k)) = e.get<std::string>();
  }
  return errors;
}

}  // namespace

RanksSfm StructureFromMotionOnRanks(const pg::SfmOptions& options, const std::string& images,
                                    const std::string& workspace, const RanksReporting& reporting) {
  RanksSfm out;
  if (!render::mpi::LaunchedByMpi()) {
    out.summary = StructureFromMotion(options, images, workspace);
    return out;
  }
  const render::mpi::Session session;
  const int rank = session.rank();
  out.root = rank == 0;
  std::exception_ptr failure;
  if (rank == 0) {
    // Every other rank waits for one broadcast: the jobs, or "" when rank 0 maps no chunks.
    bool handed_out = false;
    try {
      out.summary = StructureFromMotion(options, images, workspace, [&](const std::vector<pg::ChunkMapperJob>& jobs) {
        std::string text = ChunkJobsToText(jobs);
        session.Broadcast(&text);
        handed_out = true;
        return RunShare(session, jobs, options.chunks.parallel);
      });
    } catch (...) {
      failure = std::current_exception();
    }
    if (!handed_out) {
      std::string none;
      session.Broadcast(&none);
    }
  } else {
    SetConsoleProgressEnabled(false);  // one report, rank 0's
    try {
      std::string text;
      session.Broadcast(&text);
      if (!text.empty()) RunShare(session, ChunkJobsFromText(text), options.chunks.parallel);
    } catch (...) {
      failure = std::current_exception();
    }
  }
  out.failures = GatherRankFailures(session, failure, reporting);
  if (out.failures.empty()) session.Barrier();
  return out;
}

}  // namespace candi::pipeline

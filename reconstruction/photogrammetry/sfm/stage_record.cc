#include "reconstruction/photogrammetry/sfm/stage_record.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/sha256.h"
#include "reconstruction/photogrammetry/sfm/colmap_database.h"
#include "reconstruction/photogrammetry/sfm/sift_matching.h"

namespace candi::photogrammetry {

namespace fs = std::filesystem;

namespace {

std::string FileHash(const std::string& path) { return path.empty() ? "-" : Sha256OfFile(path); }

// The pairs of the match lists in `folder`.
std::set<std::pair<std::string, std::string>> PairsOfMatchLists(const std::string& folder) {
  std::set<std::pair<std::string, std::string>> pairs;
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(folder, ec)) {
    const auto list = MatchListPairs(entry.path().string());
    pairs.insert(list.begin(), list.end());
  }
  return pairs;
}

}  // namespace

void StageRecord::Write() const {
  std::string text =
      "# candi sfm: the inputs and the finished stages of this workspace (for --resume)\n";
  for (const std::string& line : inputs) text += "input " + line + "\n";
  for (const auto& [name, done] : stages) {
    char seconds[32];
    std::snprintf(seconds, sizeof(seconds), "%.3f", done.first);
    text += "stage " + name + " " + seconds + (done.second.empty() ? "" : " " + done.second) + "\n";
  }
  for (const std::string& chunk : chunks) text += "chunk " + chunk + "\n";
  WriteFileAtomic(path, text);
}

StageRecord StageRecord::Read(const std::string& path) {
  StageRecord r;
  r.path = path;
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "cannot read");
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    const size_t space = line.find(' ');
    const std::string key = line.substr(0, space),
                      rest = space == std::string::npos ? "" : line.substr(space + 1);
    if (key == "input") {
      r.inputs.push_back(rest);
    } else if (key == "chunk" && !rest.empty()) {
      r.chunks.insert(rest);
    } else if (key == "stage") {
      std::istringstream fields(rest);
      std::string name;
      double seconds = 0;
      if (!(fields >> name >> seconds))
        throw InputError(path, "line " + std::to_string(number),
                         "a stage line: stage <name> <seconds>");
      std::string found;
      std::getline(fields >> std::ws, found);
      r.stages[name] = {seconds, found};
    } else {
      throw InputError(path, "line " + std::to_string(number),
                       "'" + key + "': expected input, stage or chunk");
    }
  }
  return r;
}

std::vector<std::string> StageInputs(const SfmOptions& o, const std::vector<std::string>& images) {
  const PairSelectionOptions& p = o.pairs;
  std::vector<std::string> lines = {
      "max_image_size " + std::to_string(o.max_image_size),
      "max_features " + std::to_string(o.max_features),
      "camera_model " + o.camera_model,
      "single_camera " + std::to_string(o.single_camera),
      "matching " + PairStrategyName(p.strategy) + " " + std::to_string(p.exhaustive_max_images) +
          " " + std::to_string(p.sequential_overlap) + " " +
          std::to_string(p.retrieval_neighbours) + " " + std::to_string(p.position_neighbours) +
          " " + std::to_string(p.branching) + " " + std::to_string(p.depth) + " " +
          std::to_string(p.train_descriptors) + " " + std::to_string(p.kmeans_iterations) + " " +
          std::to_string(p.seed),
      "transitive_matching " + std::to_string(p.transitive_rounds) + " " + std::to_string(p.transitive_neighbours),
      "priors " + FileHash(o.priors),
      "targets " + FileHash(o.chunks.targets),
      "picks " + FileHash(o.chunks.picks),
      "joint_adjustment " + std::to_string(o.chunks.joint.enabled) + " " +
          std::to_string(o.chunks.joint.max_link_angle_deg) + " " +
          std::to_string(o.chunks.joint.reprojection_sigma_px) + " " +
          std::to_string(o.chunks.joint.pick_sigma_px) + " " +
          std::to_string(o.chunks.joint.refine_intrinsics) + " " +
          std::to_string(o.chunks.joint.max_iterations)};
  for (const std::string& image : images) lines.push_back("photo " + image);
  return lines;
}

void ClearUnfinishedStage(const std::string& stage, const std::string& workspace) {
  const auto Path = [&](const char* relative) { return (fs::path(workspace) / relative).string(); };
  std::error_code ec;
  if (stage == "feature_extractor") {
    for (const char* f :
         {"database.db", "database.db-journal", "database.db-wal", "database.db-shm"})
      fs::remove(Path(f), ec);
  } else if (stage == "matches_importer") {
    if (fs::exists(Path("database.db"))) ClearMatches(Path("database.db"));
    fs::remove_all(Path(kTransitiveFolder), ec);
  } else if (stage == kTransitiveStage) {
    // The rounds' pairs leave the database, then their lists (a list is written whole before
    // COLMAP verifies it).
    if (fs::exists(Path("database.db"))) RemoveMatches(Path("database.db"), PairsOfMatchLists(Path(kTransitiveFolder)));
    fs::remove_all(Path(kTransitiveFolder), ec);
  } else if (stage == "mapper") {
    for (const auto& e : fs::directory_iterator(Path("sparse"), ec)) {
      // Chunked mapping keeps the chunks' own folders (sparse_chunks/) and rebuilds sparse/merged.
      fs::remove_all(e.path(), ec);
    }
  } else if (stage == "image_undistorter") {
    fs::remove_all(Path("dense"), ec);
  }
}

}  // namespace candi::photogrammetry

// The record of a `candi sfm` workspace for --resume (WORKSPACE/sfm_stages.txt): what the outputs
// depend on (the photos, the options, the priors, targets and picks by their contents) and the
// stages and chunks finished; and the clean-up of a stage that was stopped, so that it starts
// again from nothing.
// Thread-safety: none (one run a workspace).
#pragma once

#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "reconstruction/photogrammetry/sfm/colmap_runner.h"

namespace candi::photogrammetry {

// sfm_stages.txt: lines "input <what>", "stage <name> <seconds>[ <what it found>]", "chunk <name>".
struct StageRecord {
  std::string path;
  std::vector<std::string> inputs;
  std::map<std::string, std::pair<double, std::string>> stages;  // name -> seconds, what it found
  std::set<std::string> chunks;

  void Write() const;  // atomically
  // InputError naming the file and line for an unreadable file or a line of another kind.
  static StageRecord Read(const std::string& path);
};

// What the outputs depend on: the photos and every option but the thread counts (which change
// no byte) and the COLMAP executable; the priors, targets and picks by their contents.
std::vector<std::string> StageInputs(const SfmOptions& options, const std::vector<std::string>& images);

// What a stage left when it was stopped, removed before it runs again from nothing (a resumed
// extraction would give the remaining photos a camera of their own; the others would mix old and
// new results).
void ClearUnfinishedStage(const std::string& stage, const std::string& workspace);

}  // namespace candi::photogrammetry

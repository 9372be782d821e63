// A COPC file's structure as a COPC reader sees it (https://copc.io): its "copc" info VLR and the
// EPT hierarchy pages walked from the root page by their file offsets, for `candi info` and for
// anyone checking a COPC file (what Potree, QGIS and copc.js follow to find a node's points).
// Failure: InputError naming the file and the byte for an info VLR that is not 160 bytes, and
// for a hierarchy page outside the file, of a size that is not a multiple of 32, reached twice,
// or holding an entry whose key lies outside its level, whose point count is below -1 or whose
// chunk lies outside the file. Reads the file with positioned reads; thread-compatible.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "io/copc/copc_write.h"

namespace candi::io {

struct CopcSummary {
  CopcInfo info;
  uint64_t pages = 0;        // hierarchy pages reached from the root page
  uint64_t nodes = 0;        // entries of nodes (point count >= 0)
  uint64_t empty_nodes = 0;  // of them, those of no point
  uint64_t points = 0;       // the nodes' point counts summed
  // By level (0: the root) up to the deepest node's.
  std::vector<uint64_t> nodes_by_level, points_by_level;
};

// The summary of the COPC file at `path`, whose LAS metadata (as its reader gives it) is `las`;
// nullopt when the file is not COPC (no "copc" info VLR).
std::optional<CopcSummary> ReadCopcSummary(const std::string& path, const LasMetadata& las);

}  // namespace candi::io

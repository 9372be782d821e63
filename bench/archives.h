// Generated archives shared by `candi bench view` and `candi bench section`: the terraced solid
// of bench scale packed into WORK_DIR/scene-N.archive, or one an earlier --keep run left there.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace candi::bench {

// "1e7,1e8" (each in [1e3, 1e10]) and 1e9 when `billion`; std::invalid_argument naming --sizes.
std::vector<uint64_t> ParseBenchSizes(const std::string& sizes, bool billion);

// The archive of n points in `dir`: reused when `keep` and a kept one holds n points (then
// *pack_seconds is 0), else packed (with progress, named by `what`).
std::string BenchArchive(const std::string& dir, uint64_t n, bool keep, const std::string& what, double* pack_seconds);

}  // namespace candi::bench

// candi's own SIFT matcher: exact brute-force nearest neighbours, COLMAP's matching criterion,
// the same matches for any thread count and on every run.
//
// Why: COLMAP 3.8's CPU matcher (FLANN randomized kd-trees) draws from the C library's global
// rand(), which its verification threads reseed concurrently, so the same features give slightly
// different matches from run to run (even with one thread) and the whole reconstruction drifts.
// Here every descriptor is compared with every other: the dot products of COLMAP's byte
// descriptors are integers below 2^24, exact in float whatever the summation order, and ties go to
// the lowest index, as in COLMAP's own brute-force code. The matches are handed to COLMAP's
// `matches_importer --match_type raw`, which verifies them geometrically in one thread, in order.
#pragma once

#include <cstdint>
#include <functional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "reconstruction/photogrammetry/sfm/colmap_database.h"

namespace candi::photogrammetry {

// COLMAP's SiftMatchingOptions defaults.
struct SiftMatchOptions {
  float max_ratio = 0.8f;     // best angle < max_ratio x second-best angle, > 0
  float max_distance = 0.7f;  // best angle (radians between the unit descriptors) <= this, > 0
  bool cross_check = true;    // keep a match only when it is mutual
  void Check() const;         // throws std::invalid_argument naming the field
};

// Matches of descriptors a (rows_a x 128) to b (rows_b x 128): (index in a, index in b), by
// increasing index in a. For each descriptor the best and second-best dot products are found
// (strictly greater wins, so the lowest index wins a tie); a match passes when
// acos(best / 512^2) <= max_distance and acos(best) < max_ratio x acos(second).
std::vector<std::pair<int, int>> MatchSiftBruteForce(const uint8_t* a, int64_t rows_a, const uint8_t* b,
                                                     int64_t rows_b, const SiftMatchOptions& options);

// Image pairs (i < j, indices into a list sorted by name): every pair, or each image with the next
// `overlap` ones (COLMAP's sequential matching without loop detection).
std::vector<std::pair<size_t, size_t>> ExhaustivePairs(size_t count);
std::vector<std::pair<size_t, size_t>> SequentialPairs(size_t count, int overlap);

// Clears (to zero: no positive dot product, so never a best or second-best neighbour) the
// descriptors COLMAP 3.8's CPU SIFT (VLFeat) leaves unwritten, which differ from run to run and
// with the thread count (all zeros in one run, a spike of 255 in the next): VLFeat computes no
// descriptor for a keypoint in the last row of its octave's image (or past its last column), and
// COLMAP keeps whatever its buffer held. In image pixels that is the bottom 1.5 x 2^octave rows and
// the right 0.5 x 2^octave columns; with 2^octave <= sigma / 1.27 (sigma0 1.6, the lowest scale
// level -1 of 3), the keypoints within margin + 1.2 sigma of the bottom and margin + 0.4 sigma of
// the right edge, and within `margin` of the others. Seen on a 60-photo campaign of 320 x 240:
// 14 of 85,056 descriptors differed between 1 and 2 threads, all among the 332 this clears (the
// outermost pixel row alone, 71, missed three). Returns how many were cleared.
inline constexpr double kBorderRowsPerSigma = 1.2, kBorderColumnsPerSigma = 0.4;
size_t ClearBorderDescriptors(std::vector<DatabaseImage>* images, double margin = 1.0);

struct MatchListSummary {
  size_t pairs = 0;             // pairs matched
  size_t pairs_written = 0;     // pairs with at least one match (written)
  size_t matches = 0;           // in all
};
// Matches the given pairs of `images` (in parallel on `threads` threads, -1 = all; the output does
// not depend on it) and writes COLMAP's raw match list to `path` (atomically): for each pair with
// matches, "name_i name_j", one "index_i index_j" line per match and an empty line. `progress` is
// called from the calling thread with the pairs done so far. Image names must not hold
// whitespace (the list is split on it): InputError naming the image.
MatchListSummary WriteMatchList(const std::vector<DatabaseImage>& images,
                                const std::vector<std::pair<size_t, size_t>>& pairs,
                                const SiftMatchOptions& options, int threads, const std::string& path,
                                const std::function<void(size_t done, size_t total)>& progress = nullptr);

// The pairs of a match list WriteMatchList wrote (each block's first line), each pair in name
// order; none for a missing file.
std::set<std::pair<std::string, std::string>> MatchListPairs(const std::string& path);

}  // namespace candi::photogrammetry

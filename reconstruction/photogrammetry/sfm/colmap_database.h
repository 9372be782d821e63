// COLMAP's feature database (database.db, SQLite; COLMAP 3.8's schema): the images and their
// SIFT descriptors, for candi's own matcher (sift_matching.h), and the renumbering that makes the
// database the same on every run.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <set>
#include <string>
#include <utility>
#include <vector>

namespace candi::photogrammetry {

struct DatabaseImage {
  int64_t image_id = 0;
  int64_t camera_id = 0;
  std::string name;                  // relative to COLMAP's --image_path
  int64_t width = 0, height = 0;     // of its camera, pixels
  int64_t rows = 0;                  // features
  std::vector<float> xy;             // rows x 2: keypoint positions, pixels (COLMAP: 0.5 = first pixel's centre)
  std::vector<float> scale;          // rows: keypoint scales (sigma), pixels; 0 where the table has only x, y
  std::vector<uint8_t> descriptors;  // rows x 128, row-major (COLMAP stores them as unsigned bytes)
};

// Every image of the database with its keypoints and descriptors, by increasing image_id. An image
// with no features gets rows = 0. Throws InputError naming the file for a missing or unreadable
// database, a missing table, a blob whose size is not rows x cols elements, descriptors not 128
// wide, or keypoint and descriptor counts that differ.
// Read-only (SQLITE_OPEN_READONLY).
std::vector<DatabaseImage> ReadColmapDescriptors(const std::string& database_path);

// Gives the images ids 1..n in the order of their names, and the cameras ids 1..m in the order of
// their first image, in one transaction (all or nothing). COLMAP's feature_extractor numbers them
// in the order its threads finish, which differs from run to run, and the mapper's choices follow
// the ids. Only before matching: a database holding matches is an InputError, as is an image
// naming a missing camera. Returns true when anything was renumbered.
bool RenumberImagesByName(const std::string& database_path);

// Removes every match and verified pair (before COLMAP's verification runs again), in one
// transaction. InputError as RenumberImagesByName.
void ClearMatches(const std::string& database_path);

// The names of every image pair matched (the database's matches, verified or not), each pair in
// name order. InputError as ReadColmapDescriptors.
std::set<std::pair<std::string, std::string>> MatchedPairNames(const std::string& database_path);

// Removes the matches and verification of the named pairs (either order; pairs the database does
// not hold are passed over), in one transaction. InputError as RenumberImagesByName.
void RemoveMatches(const std::string& database_path, const std::set<std::pair<std::string, std::string>>& pairs);

// The names of the image pairs COLMAP's geometric verification kept (as CountVerifiedPairs), each
// pair in name order. InputError as ReadColmapDescriptors.
std::set<std::pair<std::string, std::string>> VerifiedPairNames(const std::string& database_path);

// A verified photo pair's inlier matches: keypoint index in image_a, keypoint index in image_b.
struct PairMatches {
  std::string image_a, image_b;
  std::vector<std::pair<uint32_t, uint32_t>> matches;
};

// The inlier matches of the image pairs COLMAP's verification kept (as VerifiedPairNames), by pair
// id, each as (the lower image id's name, the other's) with keypoint index pairs; `want(a, b)`, when
// given, picks the pairs to read. InputError as ReadColmapDescriptors, or for a malformed blob.
std::vector<PairMatches> ReadVerifiedMatches(
    const std::string& database_path,
    const std::function<bool(const std::string&, const std::string&)>& want = nullptr);

// The image pairs COLMAP's geometric verification kept (two_view_geometries with inliers and a
// configuration of CALIBRATED or better). InputError as ReadColmapDescriptors.
size_t CountVerifiedPairs(const std::string& database_path);

}  // namespace candi::photogrammetry

// Mapping in chunks: a campaign's sessions (the photos' folders) are mapped separately, by one
// COLMAP mapper each (in parallel), then tied into the survey frame by the total-station targets
// each chunk sees and merged into one model, with a report of how well neighbouring chunks agree.
//
// Tying: in each chunk's model the targets' picks are triangulated (pick coordinates undistorted
// with the chunk's camera first) and a robust similarity is fitted on the control targets
// (georef.h); the chunk's check targets give its check RMSE. A chunk with fewer than 3 usable
// control targets is not tied: it is reported by name with the reason and left out of the merged
// model, never merged on a guess.
//
// Merging: every tied chunk's cameras, images and points re-posed into the targets' local frame
// (survey minus LocalFrame::Auto's integer shift, reported), renumbered (cameras by chunk, images
// by name, points in chunk order): one COLMAP model whose coordinates are survey coordinates
// minus the shift.
//
// Joint adjustment (joint_adjustment.h): then the tied chunks' points are joined where verified
// matches between two chunks' photos link them, and everything is bundle-adjusted together with the
// targets' picks and the control targets' survey: the merged model is the adjusted one.
//
// Consistency: for each pair of tied chunks, each sparse point of one that has at least 5 points of
// the other within `overlap_radius` is measured against the plane those points fit: the median
// and 90th percentile of those distances, both ways, over the overlap, as tied (after the joint
// adjustment, the points they share are one).
// Thread-safety: pure functions of their files; TieChunks reads the chunks' models in parallel.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/local_frame.h"
#include "core/transform.h"
#include "reconstruction/photogrammetry/georef/georef.h"
#include "reconstruction/photogrammetry/georef/similarity_fit.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"
#include "reconstruction/photogrammetry/sfm/joint_adjustment.h"

namespace candi::photogrammetry {

struct ChunkedMappingOptions {
  std::string targets;            // surveyed targets (georef.h's CSV); "" = map in one piece
  std::string picks;              // their picks in the photos (name,image,u,v); image by file name
  SimilarityFitOptions fit;       // each chunk's similarity
  JointAdjustmentOptions joint;   // then all chunks adjusted as one (joint_adjustment.h)
  int parallel = 2;               // chunk mappers at once, >= 1
  double overlap_radius = 0.1;    // metres, > 0: the consistency report's neighbourhood
  void Check() const;
};

struct ChunkResult {
  std::string name;                       // the session folder ("s1"), "all" without folders
  std::string model_dir;                  // its mapper's largest model ("" when none)
  size_t images = 0, registered = 0, points = 0;
  bool tied = false;                      // in the survey frame (and in the merged model)
  std::string reason;                     // why not tied
  int control_used = 0, check_used = 0;   // targets in the fit and verified
  Rmse control, check;                    // metres
  std::vector<std::string> unused_targets;  // of the chunk's own picks: left out, and why
  Sim3 local_from_model;                  // into the merged model's frame
};

struct ChunkPairConsistency {
  std::string a, b;
  size_t overlap = 0;          // points (both ways) with a neighbourhood in the other chunk
  double median = 0, p90 = 0;  // metres, point to the other chunk's local plane; as tied
};

struct ChunkedMappingResult {
  std::vector<ChunkResult> chunks;
  std::vector<ChunkPairConsistency> pairs;  // tied chunks that overlap, by name
  LocalFrame frame;                         // merged model = survey - frame.origin
  JointAdjustmentResult joint;              // the chunks adjusted as one (ran: false when not)
  std::string merged_dir;
  size_t merged_images = 0, merged_points = 0;
};

// A photo's chunk: its name's folder ("s1/a.jpg" is in "s1"), "all" without one.
std::string ChunkOfName(const std::string& name);

// The chunks of a list of image names: by folder ("s1/a.jpg" is in "s1"), names without one in
// "all"; chunk names sorted, images in the given order.
std::map<std::string, std::vector<std::string>> ChunksByFolder(const std::vector<std::string>& names);

// A pixel of a photo (COLMAP's image coordinates) without the camera's lens distortion: where the
// pinhole camera of the same focal and principal point sees the same ray. SIMPLE_PINHOLE, PINHOLE,
// SIMPLE_RADIAL, RADIAL, OPENCV; others throw InputError naming the model.
Eigen::Vector2d UndistortPixel(const ColmapCamera& camera, const Eigen::Vector2d& uv);

// Triangulates the targets without model coordinates from their picks in the model's photos (picks
// name photos by file name or path; undistorted with each photo's camera first), as
// TriangulateTargets. Returns the picks in photos the model does not hold.
int TriangulateTargetsInModel(const ColmapModel& model, const std::vector<ImagePick>& picks,
                              const std::string& picks_path, std::vector<SurveyTarget>* targets);

// Ties the mapped chunks (name -> its model folder; "" for a chunk whose mapper found no model or
// that holds one photo, which is not mapped), adjusts the tied chunks as one when two or more are
// tied and options.joint.enabled (`matches`: the verified pairs' inlier matches, of which those
// between two chunks join their points; the result's joint.reason says why it did not run), and
// writes the merged model into `merged_dir` (binary). InputError for unreadable targets or picks,
// or when no chunk can be tied (each chunk's reason in the message).
ChunkedMappingResult TieChunks(const std::map<std::string, std::string>& chunk_models,
                               const std::map<std::string, std::vector<std::string>>& chunk_images,
                               const std::vector<PairMatches>& matches, const ChunkedMappingOptions& options,
                               const std::string& merged_dir);

}  // namespace candi::photogrammetry

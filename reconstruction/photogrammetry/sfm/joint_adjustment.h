// The chunks of a campaign adjusted as one. Tying each chunk to the targets on its own leaves each
// chunk's share of the targets' error in it: neighbouring chunks disagree by about their check
// RMSE. The joint adjustment joins the chunks' sparse points where verified matches between two
// chunks' photos say they are the same point, and bundle-adjusts every camera pose, every point and
// the targets together: the photos' observations (COLMAP's camera models; each chunk's focal
// length and distortion refined again, since a chunk's focal error moves its cameras along their
// axes while its points and targets stay put; one camera for all when the chunks' cameras are
// copies of one), the targets' picks, and the control targets held to their surveyed
// coordinates by their stated accuracy. Check targets are adjusted from their picks alone and
// compared with their surveyed coordinates afterwards.
//
// Joining: a match links point p of chunk A (seen at keypoint k of photo a) and point q of chunk B
// (at keypoint l of photo b); the link is kept when the two points, as tied, lie within
// `max_link_angle_deg` of each other as seen from a's and b's cameras, and joining them gives no
// photo two observations of one point. A joined point starts at its members' mean. Where the match's
// keypoint in the other chunk's photo holds no point, the point gains it as an observation when it
// projects within the same angle of it.
//
// Coordinates are the merged model's (survey minus the shift); targets are given in that frame.
// Deterministic: one thread (Ceres's multi-threaded elimination sums in no fixed order), inputs in
// their given order.
// Thread-safety: a pure function of its inputs.
#pragma once

#include <string>
#include <vector>

#include "reconstruction/photogrammetry/georef/georef.h"
#include "reconstruction/photogrammetry/sfm/colmap_database.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"

namespace candi::photogrammetry {

struct JointAdjustmentOptions {
  bool enabled = true;               // after tying, when two or more chunks are tied
  double max_link_angle_deg = 1.0;   // (0, 90): two chunks' points farther apart than this are not joined
  double reprojection_sigma_px = 1;  // > 0: a photo observation's standard deviation
  double pick_sigma_px = 1;          // > 0: a target pick's standard deviation
  bool refine_intrinsics = true;     // each camera's focal length and distortion (not its principal point)
  bool one_camera = false;           // the chunks' cameras are copies of one (candi sfm's single camera):
                                     // adjusted as one camera, which the model then holds
  int max_iterations = 100;          // >= 1: Levenberg-Marquardt iterations
  void Check() const;
};

struct JointAdjustmentResult {
  bool ran = false;
  std::string reason;                // why it did not run (empty when it ran or was not asked for)
  size_t links = 0;                  // matches that joined two chunks' points (kept)
  size_t extended = 0;               // observations in another chunk's photo added to a point (its
                                     // match there untriangulated)
  size_t links_rejected = 0;         // joins and additions refused: farther than max_link_angle_deg, or
                                     // two observations of one point in a photo
  size_t joined_points = 0;          // points that now hold observations of two or more chunks
  size_t observations = 0, points = 0, images = 0;
  double rms_before_px = 0, rms_after_px = 0;  // the photos' observations, before and after
  Rmse control, check;               // targets after the adjustment, metres (survey minus adjusted)
  int iterations = 0;
  bool converged = false;
  double seconds = 0;
};

// Adjusts `model` (the merged model of tied chunks, in the targets' local frame) in place: poses
// and points refined, joined points merged into one (their ids renumbered 1..n in order of first
// appearance), every point's error recomputed. An image's chunk is its name's folder ("s1/a.jpg" is
// in "s1", as ChunksByFolder); `matches` name images as the model does. `targets` are in the model's frame (survey minus the shift); `picks` name images by their file
// name or path. Targets with fewer than two picks in the model's photos are left out. Throws
// InputError when no control target is seen twice (nothing fixes the frame).
JointAdjustmentResult AdjustJointly(ColmapModel* model, const std::vector<PairMatches>& matches, const std::vector<SurveyTarget>& targets,
                                    const std::vector<ImagePick>& picks, const JointAdjustmentOptions& options);

}  // namespace candi::photogrammetry

// Georeferencing with total-station targets: a robust similarity (similarity_fit.h) from model
// coordinates to survey coordinates (E, N, H in metres, e.g. UTM 49S), fitted on the control
// targets and verified on the check targets.
//
// Targets CSV (header required, columns in any order, names case-insensitive, '#' comments):
//   name,E,N,H,role,accuracy[,x,y,z]
//   name      unique target name (no commas)
//   E,N,H     survey coordinates, metres (easting, northing, height)
//   role      control (used in the fit) | check (only verified)
//   accuracy  the survey's 1-sigma accuracy of this target, metres, > 0 (weights the fit)
//   x,y,z     optional: the target's model coordinates; leave all three empty (or omit the
//             columns) for a target that is picked in images instead.
// Picks CSV (header required): name,image,u,v — one row per observation of a target in an image:
//   image is the image name as in the model (COLMAP's images.txt NAME); u, v are pixels in COLMAP's
//   convention (the image's top-left corner is (0, 0), the first pixel's centre (0.5, 0.5)) in the
//   undistorted image (pinhole projection). A target picked in >= 2 images is triangulated (DLT,
//   then Ceres minimising the reprojection error) and its RMS reprojection error reported.
//   Picks in images the model does not have are skipped (another chunk's images) and counted.
//
// Chunks: separately processed chunks are tied into one frame by running the georeferencing per
// chunk with the same surveyed targets (each chunk with its own model coordinates or picks); every
// chunk then lands in the survey frame. Targets a chunk does not see are reported as unused.
//
// Frames: residuals are T * model - survey (dX = dE, dY = dN, dZ = dH). The result carries the
// automatic integer shift of the targets (LocalFrame::Auto), which outputs are written in.
// Failure: bad files throw InputError naming the file, line and field; fewer than 3 usable control
// targets throws InputError naming the targets file.
#pragma once

#include <limits>
#include <map>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/local_frame.h"
#include "core/point_cloud.h"
#include "core/transform.h"
#include "reconstruction/photogrammetry/georef/similarity_fit.h"

namespace candi::photogrammetry {

enum class TargetRole { kControl, kCheck };
std::string TargetRoleName(TargetRole role);  // "control", "check"

struct SurveyTarget {
  std::string name;
  Eigen::Vector3d survey = Eigen::Vector3d::Zero();  // E, N, H, metres
  TargetRole role = TargetRole::kControl;
  double accuracy = 0.01;                            // metres, > 0
  bool has_model = false;                            // model coordinates known
  Eigen::Vector3d model = Eigen::Vector3d::Zero();   // model frame
  double reprojection_px = std::numeric_limits<double>::quiet_NaN();  // RMS, when triangulated
  int views = 0;                                     // images it was triangulated from
  std::string unused_reason;                         // non-empty: left out, and why
  int line = 0;                                      // line in the targets file
};

std::vector<SurveyTarget> ReadSurveyTargets(const std::string& path);

struct ImagePick {
  std::string target, image;
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();  // pixels, COLMAP's convention
  int line = 0;
};
std::vector<ImagePick> ReadImagePicks(const std::string& path);

using ProjectionMatrix = Eigen::Matrix<double, 3, 4>;  // x_image ~ P [X; 1], model frame

struct Triangulation {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // model frame
  double rms_px = 0, max_px = 0;                    // reprojection errors after refinement
  bool in_front = true;                             // in front of every camera
  bool converged = false;
};
// Linear (DLT, normalised rows) then nonlinear (Ceres) triangulation from >= 2 views.
// Throws std::invalid_argument for fewer than 2 views or mismatched sizes.
Triangulation TriangulatePoint(const std::vector<ProjectionMatrix>& cameras,
                               const std::vector<Eigen::Vector2d>& uv);

// Triangulates every target without model coordinates from its picks in `cameras` (by image
// name). A pick naming an unknown target throws InputError (picks file, line, field 'name'); a
// target seen in fewer than 2 known images, or triangulated behind a camera, is marked unused.
// Returns the number of picks in images `cameras` does not have (skipped).
int TriangulateTargets(const std::vector<ImagePick>& picks, const std::string& picks_path,
                       const std::map<std::string, ProjectionMatrix>& cameras,
                       std::vector<SurveyTarget>* targets);

struct Rmse {
  int count = 0;
  double x = 0, y = 0, z = 0, xy = 0, d3 = 0;  // metres
};
// The RMSE of residual vectors per axis, horizontally and in 3D (count 0 and zeros for none).
Rmse RmseOf(const std::vector<Eigen::Vector3d>& residuals);

struct GeorefResult {
  Sim3 survey_from_model;                    // survey = T * model (world coordinates)
  LocalFrame frame;                          // the targets' integer shift (outputs use it)
  SimilarityFitResult fit;                   // over the used control targets, in their order
  std::vector<SurveyTarget> targets;         // as given (with triangulations)
  std::vector<Eigen::Vector3d> residuals;    // per target: T * model - survey (zero when unused)
  std::vector<bool> outlier;                 // per target: flagged (control: left out of the fit)
  Rmse control, check;                       // control over the fit's inliers; check over all used
};

// Fits the similarity on the control targets with model coordinates and verifies the checks.
// Throws InputError(targets_path) when fewer than 3 control targets are usable.
GeorefResult Georeference(const SimilarityFitOptions& options,
                          const std::vector<SurveyTarget>& targets,
                          const std::string& targets_path);

// Re-expresses a chunk of model points in the survey frame `out` (positions in double; normals
// rotated): x_out_local = s R (x_local + o_in) + t - o_out, the constant part computed once.
void ApplySimilarity(const Sim3& survey_from_model, const LocalFrame& out, PointCloud* cloud);

}  // namespace candi::photogrammetry

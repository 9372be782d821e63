// A synthetic photo campaign with its ground truth: a stepped temple stand-in (square terraces
// with carved relief panels on every wall, stone-block and fine texture, one sun) photographed as
// operators do it. Each terrace wall is walked at `wall_distance` from it, the camera level and
// facing the wall, in `heights` rows, photos `overlap` apart (the step is the footprint times
// 1 - overlap), the corners turned on an arc; an optional UAV ring looks down from above. The
// walks are split into `chunks` sessions, each a sector of the building (every terrace and row of
// its part of the perimeter); sessions are photographed separately, so they share no photo, only
// the stone at their borders. Survey targets (four-quadrant discs) are painted on the walls above
// the panels at two heights, four a session, and on the ground for the UAV ring.
//
// The building is sized from the count: the walks' length is what N photos at this step cover,
// so 60 photos make a single terrace about 4 m across and 2,000 photos several terraces about
// 40 m across, each photo still 2 m from its wall.
//
// Frames: the world frame is metres, z up, the building centred on the origin, the ground z = 0.
// The survey frame (targets, priors, truth) is the world shifted by kCampaignSurveyOrigin (UTM
// 49S-like easting and northing, a height), so survey coordinates are ~10^6 m with mm detail.
//
// Written by WriteCampaign into OUT (see docs/guide/campaign.md):
//   <chunk>/<chunk>_NNNN.jpg   the photos of each session (JPEG with EXIF focal length)
//   targets.csv                surveyed targets, georef's format (name,E,N,H,role,accuracy)
//   picks.csv                  where each target is seen in each photo (name,image,u,v), 0.3 px
//   priors.csv                 GPS-like camera positions (name,E,N,H,sigma), when gps_sigma > 0
//   truth/cameras.csv          every photo's true pose and intrinsics (survey frame)
//   truth/surface.ply          points on the true visible surface (survey frame, shifted)
//   campaign.json              the options, the building and the counts
// Thread-safety: pure functions; photos are rendered in parallel, the bytes do not depend on the
// thread count.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/progress.h"
#include "reconstruction/photogrammetry/pinhole_camera.h"
#include "reconstruction/photogrammetry/scenes/synthetic_views.h"

namespace candi::photogrammetry {

inline const Eigen::Vector3d kCampaignSurveyOrigin(410000.0, 9159000.0, 265.0);

struct CampaignOptions {
  int photos = 60;              // all photos, walks and UAV ring, [8, 5000]
  int width = 320;              // pixels, the long side (landscape; height = 3/4), [64, 8192]
  int chunks = 3;               // sessions the walks are split into, [1, 64]
  int uav_photos = 0;           // of `photos`, on a ring above the building (its own session), >= 0
  int heights = 2;              // camera rows along each wall, [1, 4]
  double wall_distance = 2.0;   // metres from the wall, [0.5, 10]
  double overlap = 0.6;         // between neighbouring photos of a row, [0.2, 0.9]
  double fov_degrees = 60;      // horizontal field of view, (20, 120)
  double focal_mm = 20.0;       // the EXIF focal length (the sensor width follows), > 0
  double gps_sigma = 0;         // metres; > 0 writes priors.csv with this noise per axis, >= 0
  double noise_sigma = 0;       // sensor noise, grey levels (0-255), >= 0
  int supersample = 2;          // rays per pixel side, [1, 8]
  int jpeg_quality = 92;        // [50, 100]
  uint64_t seed = 1;            // texture, carvings, noise, survey and pick errors
  void Check() const;
};

struct CampaignPhoto {
  std::string name;     // "<chunk>_NNNN.jpg", unique in the campaign
  std::string chunk;    // "s1", "s2", ... for the walks' sessions, "uav" for the ring
  int terrace = -1;     // the wall it faces (0 = the lowest), -1 for the UAV ring
  int row = -1;         // camera row, -1 for the UAV ring
  double walk = 0;      // position along its row's loop, [0, 1) (0 = the south-west start)
  PinholeCamera camera; // true pose, world frame
};

struct CampaignTarget {
  std::string name;     // "T01", ... walls; "G1", ... ground
  std::string chunk;    // the session it was placed for
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // world frame, on the surface
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ(); // the surface's outward normal there
  double radius = 0.08;
  bool check = false;   // a check target (verified, not used in the fit)
};

struct Campaign {
  CampaignOptions options;
  SyntheticScene scene;                   // carvings and targets included
  std::vector<double> terrace_half_sides; // metres, lowest first
  std::vector<double> terrace_floors;     // the floor each terrace's walk stands on, metres
  double wall_height = 0;                 // each terrace's wall above its floor, metres
  std::vector<std::string> chunks;        // session names, in order
  std::vector<CampaignPhoto> photos;      // sessions in order, each in walking order
  std::vector<CampaignTarget> targets;
  Eigen::Vector3d ToSurvey(const Eigen::Vector3d& world) const { return world + kCampaignSurveyOrigin; }
};

// The campaign's geometry (no rendering). Throws std::invalid_argument for invalid options.
Campaign PlanCampaign(const CampaignOptions& options);

// How the photos are rendered (texture, supersampling, noise, seed).
SyntheticViewsOptions CampaignRenderOptions(const CampaignOptions& options);
// The photos in memory, with their true depth (world frame, no file written), named as the
// campaign names them but ".png" (WriteSyntheticImages writes PNG); the pixels WriteCampaign
// encodes as JPEG. In parallel.
std::vector<SyntheticView> RenderCampaignViews(const Campaign& campaign);

// Renders every photo (in parallel, each written as it is done) and writes the files listed in
// the file comment into `output_dir` (created; an existing campaign there is refused unless
// `overwrite`). Progress counts photos. Returns the plan. InputError when OUT cannot be written.
Campaign WriteCampaign(const CampaignOptions& options, const std::string& output_dir, bool overwrite = false,
                       const ProgressCallback& progress = nullptr);

}  // namespace candi::photogrammetry

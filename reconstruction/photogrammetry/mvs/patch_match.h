// CPU multi-view PatchMatch stereo: a depth and a normal per pixel of every reference image.
//
// Per reference view (Galliani et al., "Massively Parallel Multiview Stereopsis by Surface Normal
// Diffusion" (Gipuma), ICCV 2015; Schönberger et al., "Pixelwise View Selection for Unstructured
// Multi-View Stereo" (COLMAP), ECCV 2016):
//  1. source views from the sparse model's shared points (source_views.h), or, without tracks, by
//     triangulation angle at the scene in front of the reference camera;
//  2. random initialisation of depth (inverse-depth uniform in the range) and normal (facing the
//     camera);
//  3. `iterations` rounds of red-black (checkerboard) sweeps: each pixel of one colour takes the
//     best of its own plane and the planes of eight neighbours of the other colour (Gipuma's
//     pattern at distances 1 and 5), then tries random perturbations of depth and normal
//     (refinement, shrinking each round). The cost of a plane is 1 - NCC between the reference
//     window (bilateral weights, optionally) and its plane-induced homography into each source
//     view, averaged over the best half of the sources (occlusion robustness);
//  4. a geometric-consistency filter against the neighbours' depth maps (its sources and the
//     views that have it as a source): a pixel is kept when at least `min_consistent_views`
//     neighbours see it back at the same place (forward-backward
//     reprojection error in pixels) and depth (relative), and its cost is below `max_cost`.
//
// Determinism: every random draw is HashIndex(seed, pixel, stream(view, round, colour)) and a
// checkerboard half-sweep reads only the other colour, so results are bit-identical for any thread
// count. Frames: depths are camera-frame z (metres, model units); normals are camera-frame unit
// vectors pointing towards the camera (n . ray < 0), as COLMAP stores them.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/image.h"
#include "core/progress.h"
#include "reconstruction/photogrammetry/mvs/source_views.h"
#include "reconstruction/photogrammetry/pinhole_camera.h"

namespace candi::photogrammetry {

struct PatchMatchOptions {
  int window_radius = 4;            // matching window half-size, pixels at the working scale, [1, 15]
  int window_step = 2;              // sample every step-th pixel of the window, [1, window_radius]
  int iterations = 3;               // red-black rounds (propagation + refinement), [1, 50]
  int num_source_views = 4;         // source views per reference, [1, 32]
  int num_check_views = 12;         // views the filter and fusion check a depth against, [sources, 64]
  double resolution_scale = 1.0;    // images resampled by this factor first, (0, 1]
  double depth_min = 0;             // depth range, model units; 0 and 0: from the sparse points
  double depth_max = 0;             //   (percentiles, widened) or the option when set, 0 < min < max
  double min_triangulation_angle_deg = 2;  // source views with a smaller angle are skipped, [0, 60)
  double max_distance_ratio = 2;    // source views: median distance ratio to the shared points, >= 1
  double bilateral_sigma_color = 0.15;     // bilateral weight, grey in [0,1]; 0 = plain NCC
  double bilateral_sigma_spatial = 0;      // pixels; 0 = window_radius
  double min_texture = 0.01;        // reference window grey std-dev below this: no depth, >= 0
  double max_cost = 0.4;            // kept pixels: cost (1 - NCC) below this, (0, 2]
  double max_reprojection_error_px = 1.5;  // geometric consistency, pixels, > 0
  double max_depth_error = 0.01;    // geometric consistency: |d' - d| / d, > 0
  int min_consistent_views = 2;     // geometric consistency: sources agreeing, [0, 32]; 0 = off
  uint64_t seed = 1;
  int threads = 0;                  // 0 = all cores
  SourceViewOptions Sources() const;  // the views, the angle and the distance ratio
  void Check() const;
};

struct StereoImage {
  std::string name;
  Image8 image;            // grey, RGB or RGBA at the camera's size
  PinholeCamera camera;
};

struct StereoInput {
  std::vector<StereoImage> images;
  std::vector<Eigen::Vector3d> sparse_points;  // model frame; depth ranges when not set in options
  // Per sparse point, the images that observe it (indices into `images`): the sources come from
  // the tracks and a photo's depth range from the points it observes. Empty: no tracks (the
  // geometric source rule; depth ranges from every point projected).
  std::vector<std::vector<int>> point_views;
};

struct DepthNormalMap {
  PinholeCamera camera;              // at the working resolution
  ImageF depth;                      // 1 channel; 0 = no depth (filtered out or never valid)
  ImageF normal;                     // 3 channels, camera frame, unit; 0 where depth is 0
  ImageF cost;                       // 1 channel, 1 - NCC of the final plane
  Image8 color;                      // RGB at the working resolution (for fusion)
  std::vector<int> source_views;     // indices into the input images
  std::vector<int> check_views;      // the filter's and fusion's (source_views.h); not in map files
};

// An image at the working resolution, ready to match: RGB and grey in [0, 1].
struct StereoView {
  PinholeCamera camera;
  Image8 color;              // RGB
  std::vector<float> grey;   // row-major
  Eigen::Matrix3d K, K_inv;
  size_t Bytes() const;
};

// The image resampled by `scale` (ResampleArea); InternalError for an invalid camera or an image
// whose size differs from its camera.
StereoView PrepareStereoView(const StereoImage& image, double scale);

struct PatchMatchResult {
  std::vector<DepthNormalMap> maps;  // one per input image, same order
  uint64_t valid_pixels = 0;         // after filtering, over all maps
  uint64_t total_pixels = 0;
};

// An RGB image resampled to width x height by area averaging (OpenCV's INTER_AREA), as PatchMatch
// resamples its inputs for resolution_scale < 1.
Image8 ResampleArea(const Image8& rgb, int width, int height);

// The depth range of a camera from the sparse points in front of it and inside it (2nd and 98th
// percentiles, widened by 0.75 and 1.25), or from all points in front when fewer than 8 fall
// inside; the options' range when set. std::invalid_argument when no point is in front.
std::pair<double, double> StereoDepthRange(const PatchMatchOptions& options, const PinholeCamera& camera,
                                           const std::vector<Eigen::Vector3d>& points);
// Every image's views (source_views.h) and depth range (StereoDepthRange over the points it and
// its neighbours observe when the input has tracks, else over every point). An image with no
// point in front of it gets no sources (an empty map); std::invalid_argument when none has one.
struct StereoPlan {
  std::vector<ViewLinks> links;
  std::vector<std::pair<double, double>> ranges;
};
StereoPlan PlanStereo(const PatchMatchOptions& options, const StereoInput& input);

// PatchMatch for one reference (`ref_index` numbers it in the campaign: its random streams)
// against its sources; the map before the consistency filter. `swept(n)` reports n more pixel
// sweeps. A reference without sources gets an empty map (no depth anywhere).
DepthNormalMap MatchReference(const PatchMatchOptions& options, const StereoView& ref, int ref_index,
                              const std::vector<const StereoView*>& sources, const std::vector<int>& source_indices,
                              std::pair<double, double> depth_range, const std::function<void(uint64_t)>& swept);

// The consistency and cost filter of one map against its neighbours' maps before their filter
// (NeighbourViews; any order); pixels that fail lose their depth and normal.
void FilterDepthMap(const PatchMatchOptions& options, const std::vector<const DepthNormalMap*>& neighbours,
                    DepthNormalMap* map);

// Runs PatchMatch on every image as reference, then the consistency filter. Throws
// std::invalid_argument for bad options, InputError-free (inputs come from the caller); an image
// whose camera is invalid or whose size differs from its camera throws InternalError (CANDI_CHECK).
// Progress: reference pixels swept (done, total) over all rounds.
PatchMatchResult RunPatchMatch(const PatchMatchOptions& options, const StereoInput& input,
                               const ProgressCallback& progress = nullptr);

}  // namespace candi::photogrammetry

// Synthetic multi-view stereo scene rendered by candi itself: a terraced block (two boxes at
// different heights and a slanted ramp face) on a ground plane — a small stand-in for a temple
// corner — with a seeded procedural solid texture, lit by one directional Lambertian light, seen by
// N pinhole cameras on an arc looking at it. Each image is ray-cast exactly (supersampled pixel
// area); only projection, texture, the light and optional Gaussian noise are simulated.
//
// World frame: metres, z up, the ground is z = 0, the block is centred on the origin (about
// 3.2 x 2 x 0.9 m). Thread-safety: the functions are pure; results depend only on the options.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/image.h"
#include "reconstruction/photogrammetry/pinhole_camera.h"

namespace candi::photogrammetry {

struct SyntheticViewsOptions {
  int views = 6;                   // cameras on the arc, >= 1
  int width = 160, height = 120;   // image size, pixels, >= 8 each
  double arc_degrees = 60;         // azimuth span of the arc, degrees, in [0, 360)
  double elevation_degrees = 35;   // camera elevation above the horizon, degrees, in (0, 90)
  double distance = 5.5;           // camera distance from the scene centre, metres, > 2
  double fov_degrees = 55;         // horizontal field of view, degrees, in (5, 150)
  double texture_cell = 0.04;      // texture lattice spacing, metres, > 0
  int supersample = 3;             // rays per pixel side (pixel-area integration), in [1, 8]
  double noise_sigma = 0;          // Gaussian image noise, grey levels (0-255 scale), >= 0
  bool textureless = false;        // constant albedo (degenerate case for tests)
  uint64_t seed = 1;               // texture and noise
  void Check() const;
};

struct SyntheticView {
  std::string name;        // "view_NNN.png"
  Image8 image;            // RGB
  PinholeCamera camera;
  ImageF depth;            // true camera-frame depth at each pixel centre, metres; 0 = no surface
};

// Renders the views (in arc order).
std::vector<SyntheticView> RenderSyntheticViews(const SyntheticViewsOptions& options);

// The distance along the ray origin + t * direction (direction need not be unit; t in its units)
// to the first surface of the scene, or a negative value when the ray misses.
double SyntheticSceneRayHit(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction);

// Points on the visible surface of the scene (the true depth of every `stride`-th pixel of every
// view, back-projected): a stand-in for a sparse model's points (depth ranges, tests).
std::vector<Eigen::Vector3d> SyntheticSparsePoints(const std::vector<SyntheticView>& views,
                                                   int stride = 8);

// Accuracy and completeness of dense results on the synthetic scene. A point's error is the
// smallest, over the views seeing it, of |distance from the camera - distance to the first
// surface along the same ray| / that distance (a relative depth error along a viewing ray).
struct SyntheticDenseScore {
  uint64_t points = 0;
  double accuracy = 0;       // share of points with error <= tolerance
  double completeness = 0;   // share of stereo-observable pixels (their true surface point is also
                             // seen, unoccluded and in frame, by another view) whose depth is
                             // within tolerance
  double completeness_all = 0;  // the same share over every pixel with a true depth
  double median_error = 0;   // relative
};
// `depths[k]` is view k's depth map (0 = none) at any resolution (scaled to view k's camera);
// `points` in the world frame.
SyntheticDenseScore ScoreSyntheticDense(const std::vector<SyntheticView>& views,
                                        const std::vector<ImageF>& depths,
                                        const std::vector<Eigen::Vector3d>& points,
                                        double tolerance = 0.01);

// Writes each view's image as DIR/<name> (PNG; DIR created if missing).
void WriteSyntheticImages(const std::vector<SyntheticView>& views, const std::string& dir);

}  // namespace candi::photogrammetry

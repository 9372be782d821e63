// Synthetic multi-view stereo scenes rendered by candi itself: convex solids with a seeded
// procedural solid texture, lit by one directional Lambertian light, seen by pinhole cameras. Each
// image is ray-cast exactly (supersampled pixel area); only projection, texture, the light, painted
// survey targets and optional Gaussian noise are simulated.
//
// The default scene (RenderSyntheticViews(options), the scoring functions): a terraced block (two
// boxes at different heights and a slanted ramp face) on a ground plane — a small stand-in for a
// temple corner — seen by N cameras on an arc. World frame: metres, z up, the ground is z = 0, the
// block is centred on the origin (about 3.2 x 2 x 0.9 m). Other scenes and cameras (candi demo's
// southeast corner): RenderSyntheticScene.
// Thread-safety: the functions are pure; results depend only on their arguments.
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
  std::string name_prefix = "view";  // images are <prefix>_NNN.png
  void Check() const;
};

// A convex solid {X : n_i . X <= d_i for every i} (unit n_i) with an albedo (RGB in [0, 1]).
struct SyntheticSolid {
  std::vector<std::pair<Eigen::Vector3d, double>> planes;
  Eigen::Vector3d albedo = Eigen::Vector3d::Constant(0.7);
};
// The axis-aligned box [lo, hi].
SyntheticSolid SyntheticBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3d& albedo);

// A survey target painted on a surface: a disc of this radius around `center` (a point on the
// surface), in four black and white quadrants, as total-station photo targets are.
struct SyntheticMarker {
  std::string name;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double radius = 0.1;
};

// A relief carved into a planar face of a solid: inside the rectangle [0, width] x [0, height] of
// the face (u along `u_axis`, v along `v_axis`, from `origin`, a point on the face), the surface lies
// Depth(u, v) behind the face, in [0, depth]: a background cut to `depth` with figures (seeded
// blobs taller than wide) standing proud of it, and a frame that ramps to the face at the border,
// so the carved surface is continuous. The outward normal of the face is u_axis x v_axis.
// The carving must lie on an exposed face and its recess inside its solid (no other solid there).
struct SyntheticCarving {
  int solid = -1;                                     // index into SyntheticScene::solids
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();   // the rectangle's (0, 0), on the face
  Eigen::Vector3d u_axis = Eigen::Vector3d::UnitX();  // unit, along the face
  Eigen::Vector3d v_axis = Eigen::Vector3d::UnitZ();  // unit, along the face, across u_axis
  double width = 1, height = 1, depth = 0.04;         // metres, > 0
  uint64_t seed = 1;                                  // the figures
  double Depth(double u, double v) const;             // metres behind the face, 0 outside
};

struct SyntheticScene {
  std::vector<SyntheticSolid> solids;               // their union is the scene
  Eigen::Vector3d light = Eigen::Vector3d(0.45, -0.55, 0.70).normalized();  // towards the light
  std::vector<SyntheticMarker> markers;
  std::vector<SyntheticCarving> carvings;
  // The light a surface facing away from the sun still gets (the sky's), of the full: shading is
  // ambient + (1 - ambient) * max(0, n . light).
  double ambient = 0.3;
  // > 0: the albedo also varies by stone block, cells of this size (metres; half as tall), so
  // that distant views (a UAV's) see texture the fine lattice averages away. 0: none.
  double block_size = 0;
  // The distance along origin + t * direction (t in direction's units) to the first surface, or a
  // negative value when the ray misses.
  double RayHit(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const;
  // True when `point` (on a surface) is in the camera's frame and not hidden by the scene.
  bool Sees(const PinholeCamera& camera, const Eigen::Vector3d& point) const;
};
// The default scene (the terraced block).
const SyntheticScene& TerracedBlockScene();

struct SyntheticView {
  std::string name;        // "view_NNN.png"
  Image8 image;            // RGB
  PinholeCamera camera;
  ImageF depth;            // true camera-frame depth at each pixel centre, metres; 0 = no surface
};

// Renders one view of `scene` (of `options`, as RenderSyntheticScene uses them); `index` numbers
// the view (its name, its noise).
SyntheticView RenderSyntheticView(const SyntheticScene& scene, const PinholeCamera& camera,
                                  const SyntheticViewsOptions& options, int index);
// Renders the default scene's views (in arc order).
std::vector<SyntheticView> RenderSyntheticViews(const SyntheticViewsOptions& options);
// Renders `scene` from `cameras` (each with its own size); of `options`, only texture_cell,
// supersample, noise_sigma, textureless, seed and name_prefix are used. Views in parallel.
std::vector<SyntheticView> RenderSyntheticScene(const SyntheticScene& scene,
                                                const std::vector<PinholeCamera>& cameras,
                                                const SyntheticViewsOptions& options);
// A pinhole camera at `eye` looking at `target` (z up), with this horizontal field of view.
PinholeCamera LookAtCamera(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, int width,
                           int height, double fov_degrees);

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

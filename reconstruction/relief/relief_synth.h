// Procedural relief panels and simulated old photographs of them, with exact depth.
//
// A panel (default 2.7 m x 0.92 m, carving up to 0.15 m, like the Karmawibhangga panels) is a
// height field z(x, y) in metres above the wall: a raised frame, 3-6 carved figures (head,
// headdress, torso with clothing folds, arms, standing or seated legs) and ornament (trees,
// rosettes, vessels), weathered. It is rendered orthographically into a grey "old photo" that
// carries only what the 1890 photos call for; each effect has a switch, and its random range is
// fixed and documented on the field. Depth ground truth is exact (relief_image.h convention).
//
// Deterministic: panel `index` of a series depends only on (seed, index), not on thread count or
// on the other panels. Thread-safe (no shared state).
#pragma once

#include <cstdint>

#include "core/image.h"
#include "reconstruction/relief/panel_size.h"

namespace candi::relief {

struct OldPhotoOptions {
  // Raking light: elevation above the wall plane, degrees, drawn from [min, max] within (0, 90).
  double light_elevation_min_deg = 15, light_elevation_max_deg = 35;
  // Azimuth in the panel frame (0 = from the right, 90 = from above), drawn from [min, max].
  double light_azimuth_min_deg = 100, light_azimuth_max_deg = 170;
  bool shadows = true;  // cast shadows of the raking light (1 mm penumbra); ambient U[0.12, 0.3]
  bool stains = true;   // stone albedo U[0.45, 0.7], mottling +-15 %, 2-6 stains up to 45 % darker
  bool blur = true;     // lens blur: Gaussian, sigma U[0.5, 2.0] mm on the panel
  bool grain = true;    // film grain: Gaussian, sigma U[0.01, 0.04] of full scale, 1-pixel clumps
  bool tone = true;     // tone curve: gamma U[0.7, 1.4], then an S-curve of strength U[0, 0.5]
  bool fading = true;   // fading: contrast x U[0.55, 0.9] towards a base U[0.45, 0.65];
                        // vignetting: brightness x (1 - U[0, 0.35] r^2), r = 1 at the corners
  void Check() const;   // throws std::invalid_argument naming the field
};

struct SynthOptions {
  int width = 800;         // pixels along the panel, [32, 16384]; height from the aspect ratio
  double width_m = kPanelWidthM;    // panel width, m, > 0
  double height_m = kPanelHeightM;  // panel height, m, > 0
  double depth_m = kPanelDepthM;    // maximum relief depth (front plane), m, > 0
  uint64_t seed = 1;       // the series; panel i depends on (seed, i) only
  OldPhotoOptions photo;
  void Check() const;
  int Height() const;      // pixels, rounded from the aspect ratio, >= 1
  double PixelM() const { return width_m / width; }
};

struct PhotoSimulation {
  ImageF photo;                      // grey [0, 1], same size as the height field
  double light_azimuth_deg = 0;      // the light actually drawn
  double light_elevation_deg = 0;
};

struct SynthPanel {
  ImageF height_m;  // z above the wall, metres, [0, depth_m)
  ImageF albedo;    // stone reflectance [0, 1]
  ImageF depth;     // depth levels (relief_image.h): 255 (depth_m - z) / depth_m
  PhotoSimulation photo;
  double pixel_m = 0;
};

// The height field of panel `index` (metres, width x Height() pixels, y down the image).
ImageF ReliefHeightField(const SynthOptions& options, uint64_t index);

// Stone albedo with mottling and stains (constant when !options.stains).
ImageF StoneAlbedo(const OldPhotoOptions& options, int width, int height, double pixel_m,
                   uint64_t seed);

// Renders height_m (metres; pixel_m metres per pixel) orthographically under a raking light into
// an old photo. albedo: same size, or empty for a uniform 0.6.
PhotoSimulation SimulateOldPhoto(const OldPhotoOptions& options, const ImageF& height_m,
                                 const ImageF& albedo, double pixel_m, uint64_t seed);

// Panel `index` of the series: height field, albedo, photo and depth levels.
SynthPanel SynthesizePanel(const SynthOptions& options, uint64_t index);

}  // namespace candi::relief

// Training pairs (photo, depth) for the relief network, from scans of visible panels or from
// synthetic panels, and the paper's augmentation.
//
// A scan (any PointCloud: PLY, LAS, XYZ ...) is rendered orthographically: the panel plane is
// either the cloud's own x-y plane (frame "panel": x along the wall, y up, z out) or found by PCA
// (frame "auto": largest spread = x, smallest = z, z pointing to the side where the points are
// sparse, i.e. away from the wall). The wall (z = 0) is the 2nd percentile of z. Each pixel keeps
// the front-most point (a z-buffer); holes up to `fill_holes` pixels wide are filled from their
// neighbours, larger ones stay "no data" (level 0). The photo is simulated from the rendered
// height with the scan's colour as albedo (the same renderer as the synthetic panels), or is the
// scan's own grey (`relight` false).
//
// Files: DIR/train/NNNNNN_photo.png (8-bit grey) + NNNNNN_depth.png (16-bit levels), the same in
// DIR/val, and DIR/dataset.txt ("key value" lines: pixels_per_m, depth_m, patch, counts).
// Deterministic for a seed. Bad files throw InputError naming the path.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/point_cloud.h"
#include "reconstruction/relief/relief_synth.h"

namespace candi::relief {

struct ScanRasterOptions {
  double pixels_per_m = 800 / kPanelWidthM;  // resolution of the render, pixels per metre, > 0
  std::string frame = "auto";       // "auto" (PCA) or "panel" (the cloud's own axes)
  double depth_m = kPanelDepthM;    // front plane above the wall, m, > 0
  int fill_holes = 3;               // fill holes up to this many pixels from data, [0, 64]
  bool relight = true;              // simulate a raking-light photo; false: the scan's grey
  OldPhotoOptions photo;            // how the photo is simulated (relight)
  uint64_t seed = 1;
  void Check() const;
};

struct TrainingPair {
  ImageF photo;  // grey [0, 1]
  ImageF depth;  // levels; < kMinValidLevel = no data
};

// Renders a scan into a full-panel pair; throws InputError(path) if it has fewer than 3 points
// or no extent.
TrainingPair RasterizeScan(const ScanRasterOptions& options, const PointCloud& cloud,
                           const std::string& path);

struct PatchOptions {
  int patch = 128;                  // side, pixels, >= 32 and a multiple of 32
  int stride = 64;                  // step between patches, pixels, >= 1
  double min_valid_fraction = 0.5;  // drop patches with less valid depth, [0, 1]
  void Check() const;
};

// Cuts patch x patch pairs on a grid (the last row/column aligned to the border).
std::vector<TrainingPair> CutPatches(const PatchOptions& options, const TrainingPair& panel);

struct AugmentOptions {
  double rotate_probability = 0.5;      // random rotation, [0, 1]
  double max_rotation_deg = 5.0;        // uniform in [-max, max]; corners become "no data"
  double flip_probability = 0.5;        // horizontal flip, [0, 1]
  double brightness_probability = 0.5;  // brightness x U[0.9, 1.1], [0, 1]
  void Check() const;
};

// The paper's augmentation, each step with its probability; depends only on (seed, index).
TrainingPair Augment(const AugmentOptions& options, const TrainingPair& pair, uint64_t seed,
                     uint64_t index);

// Writes pairs as DIR/NNNNNN_photo.png + NNNNNN_depth.png, numbered from `first`.
void WritePairs(const std::string& dir, const std::vector<TrainingPair>& pairs, size_t first = 0);
// The q-quantile (rank floor(q n), clamped) of values; 0 for none.
float PercentileOf(std::vector<float> values, double q);

// The *_photo.png files of a folder, in name order; throws InputError when dir is not a folder.
std::vector<std::string> PairPhotoPaths(const std::string& dir);
// Reads every NNNNNN_photo.png / NNNNNN_depth.png pair of a folder, in name order.
std::vector<TrainingPair> ReadPairs(const std::string& dir);

}  // namespace candi::relief

// Training data for the relief depth network (`candi relief dataset`): pairs of (photo, depth)
// cut into patches, either from scans of visible panels or synthetic panels, or from real
// photographs and the depth a reconstruction gives them (reconstruction/relief).
//
// Scans and panels: OUT/train/ and OUT/val/ (one input: every 1/val_fraction-th patch validates;
// several: the last val_fraction of them), OUT/dataset.txt (pixels_per_m, depth_m, patch, counts).
// Real photos: the inputs are dense clouds in a COLMAP model's frame; OUT/views/ and OUT/holdout/
// hold whole pairs (photo, depth, mask) of the training and held-out images (with a held-out
// region: every view's pixels of that surface, see holdout_region), OUT/train/ and
// OUT/val/ the patches of the training views (the last val_fraction of them, by name, validate);
// OUT/dataset.txt says "pixels_per_m 0" (photographs have no metric resolution: the model keeps
// its own). Part of candi_pipeline_relief. Failures: std::invalid_argument for invalid options,
// InputError naming the file otherwise.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "reconstruction/relief/relief_dataset.h"
#include "reconstruction/relief/relief_photo_pairs.h"

namespace candi::pipeline {

struct ReliefDatasetOptions {
  relief::ScanRasterOptions raster;       // scans: resolution (also the panels'), frame, depth, relight, seed
  relief::PatchOptions patches;           // patch side and stride
  double val_fraction = 0.1;              // inputs (or patches, with one input) held out for validation, [0, 0.9]
  // The width of a photo input without a recorded resolution, m, > 0.
  double panel_width_m = relief::kPanelWidthM;
  // Real photographs: a COLMAP sparse model and its photos (the inputs are dense clouds in its frame).
  std::string colmap, images;
  std::vector<std::string> holdout;       // image names (or stems) kept out of training
  // A surface kept out of training (relief::ParseSceneRegion's text; empty: none): in every
  // training view the pixels whose nearest point lies in it, widened by holdout_margin pixels,
  // lose their depth and their photo (a flat grey), and holdout/ gets every view with only
  // those pixels (not widened) known: scores of a surface the network never saw.
  std::string holdout_region;
  int holdout_margin = 4;                 // pixels, [0, 64]
  relief::PhotoPairOptions photo_pairs;   // pair size (max_side), occlusion, depth normalisation
  void Check() const;
};

struct ReliefDatasetSummary {
  size_t train = 0, val = 0, inputs = 0;
};

// From scans (point files) and synthetic panels (*_photo.png with *_depth.png, or folders of them).
ReliefDatasetSummary BuildReliefDataset(const ReliefDatasetOptions& options, const std::vector<std::string>& inputs,
                                        const std::string& output_dir);

struct PhotoDatasetSummary {
  size_t views = 0, held_out = 0, train = 0, val = 0, empty_views = 0;
  size_t region_views = 0;     // views with pixels of the held-out region (in holdout/)
  uint64_t region_pixels = 0;  // known pixels of the held-out region, over holdout/
  double known_fraction = 0;  // of the views' pixels with a depth
};

// From the photos of options.colmap/options.images and dense clouds in the model's frame.
PhotoDatasetSummary BuildPhotoDataset(const ReliefDatasetOptions& options, const std::vector<std::string>& clouds,
                                      const std::string& output_dir);

}  // namespace candi::pipeline

// Buried reliefs from one old photo each (ALGORITHMS.md §3, reconstruction/relief): synthetic
// panels to train and test on, a panel's depth from its photo through the network, and its
// metric points. What `candi relief synth | predict | points` write, and how a build runs a relief
// panel in the process that holds the network (pipeline/build.h's ReliefPanelRunner). This part
// of pipeline/ links libtorch (the library candi_pipeline_relief): only candi-relief has it.
// Units: metres; depth in levels (0 the front plane, 255 the wall). Failures:
// std::invalid_argument for invalid options, InputError naming the file otherwise.
#pragma once

#include <string>

#include "core/image.h"
#include "core/point_cloud.h"
#include "pipeline/build.h"
#include "reconstruction/relief/relief_net.h"
#include "reconstruction/relief/relief_points.h"
#include "reconstruction/relief/relief_synth.h"

namespace candi::pipeline {

// `count` synthetic panels of `options` (the series' seed) in `dir` (created):
// panel_NNNN_photo.png (8-bit grey, its resolution, light and depth in its text) and
// panel_NNNN_depth.png (16-bit levels).
void WriteSyntheticPanels(const relief::SynthOptions& options, int count, const std::string& dir);

struct PanelDepthOptions {
  relief::PredictOptions predict;  // the tiles; photo_pixels_per_m comes from width_m
  // The panel's width in the photo, m, >= 0; 0: at the model's resolution.
  double width_m = relief::kPanelWidthM;
  int threads = 1;                 // libtorch threads, [1, 256]
  void Check() const;
};

struct PanelDepth {
  ImageF depth;                    // levels, the photo's size
  double seconds = 0;              // the network's time
};

// The depth map of the photo at `photo` (PNG or JPEG, any size) by the model at `model`.
PanelDepth PredictPanelDepth(const PanelDepthOptions& options, const std::string& photo, const std::string& model);
// The depth map as an 8-bit PNG (and a 16-bit one, levels x 256, when `png16` is given).
void WritePanelDepth(const ImageF& depth, const std::string& model, const std::string& png8, const std::string& png16);

// A panel's metric points from its photo (the grey becomes the colour) and its depth map (PNG
// levels), in the panel frame (x along the wall, y up, z out).
struct PanelPoints {
  PointCloud cloud;
  int width = 0, height = 0;  // the depth map's pixels
};
PanelPoints PanelPointsOf(const relief::ReliefPointsOptions& options, const std::string& photo,
                          const std::string& depth_png);

// Runs a build's relief panels in this process (two libtorch threads), writing what
// `relief predict` and `relief points` write.
ReliefPanelRunner ReliefInProcess();

}  // namespace candi::pipeline

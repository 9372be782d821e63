// Scoring relief depth: the network beside the two classical baselines and the paper's figures,
// on held-out panels (synthetic ones by default, or pairs of real photographs), in the convention
// of relief_metrics.h.
#pragma once

#include <string>
#include <vector>

#include "core/image.h"
#include "core/progress.h"
#include "reconstruction/relief/relief_metrics.h"
#include "reconstruction/relief/relief_net.h"
#include "reconstruction/relief/relief_synth.h"

namespace candi::relief {

struct EvalPanel {
  std::string name;                   // for messages
  ImageF photo;                       // grey [0, 1]
  ImageF depth;                       // ground-truth levels
  Image8 mask;                        // empty, or 0 where the ground truth is unknown
  double light_azimuth_deg = 135;     // for linear shape from shading
  double light_elevation_deg = 25;
  double pixels_per_m = 0;            // the photo's resolution (0 = the model's)
};

struct MethodScore {
  std::string name;
  DepthMetrics metrics;
  NormalMetrics normals;
  EdgeMetrics edges;
  double seconds = 0;  // total time of the method over all panels
};

struct NamedModel {
  std::string name;
  const DepthModel* model = nullptr;
};

// Held-out synthetic panels 0..count-1 of the series `synth` (use a seed not used in training).
std::vector<EvalPanel> SyntheticEvalPanels(const SynthOptions& synth, int count);

// Pairs of real photographs (relief_photo_pairs.h) as panels: no resampling, light unknown
// (SFS assumes the default 135 / 25 degrees).
std::vector<EvalPanel> PhotoEvalPanels(const std::string& dir);

// Scores intensity-as-depth and Pentland SFS (both with oracle scale and offset, see
// relief_baselines.h) and each model (tiled prediction; a relative model whole, unstretched,
// then with the same oracle scale and offset, its name marked "*"), in that order: the depth metrics, the
// normal and the edge metrics (relief_metrics.h, with `surface`), masks honoured.
std::vector<MethodScore> EvaluatePanels(const std::vector<EvalPanel>& panels,
                                        const std::vector<NamedModel>& models,
                                        const PredictOptions& predict,
                                        const SurfaceMetricOptions& surface = {},
                                        const ProgressCallback& progress = nullptr);

// The scores of several held-out parts (each the same methods in the same order; at least one)
// averaged with each part weighing the same (not each pixel: a small part counts as much as a
// large one, as in leave-one-part-out protocols); counts and seconds are summed. Parts scored
// on no pixel of a metric are left out of that metric's mean. Throws std::invalid_argument when
// the parts' methods differ.
std::vector<MethodScore> MeanOverParts(const std::vector<std::vector<MethodScore>>& parts);

// BTS (DenseNet-161) on a visible panel, the paper's Table 2.
DepthMetrics PaperBtsMetrics();

// Fixed-width text table lines: header, and one row per method (the paper's seven metrics).
std::string MetricsTableHeader();
std::string MetricsTableRow(const std::string& name, const DepthMetrics& m);
// The same for the normal and edge metrics.
std::string SurfaceTableHeader();
std::string SurfaceTableRow(const std::string& name, const NormalMetrics& n, const EdgeMetrics& e);

}  // namespace candi::relief

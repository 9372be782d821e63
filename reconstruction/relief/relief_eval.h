// Scoring relief depth: the network beside the two classical baselines and the paper's figures,
// on held-out panels (synthetic ones by default), in the convention of relief_metrics.h.
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
  ImageF photo;                       // grey [0, 1]
  ImageF depth;                       // ground-truth levels
  double light_azimuth_deg = 135;     // for linear shape from shading
  double light_elevation_deg = 25;
  double pixels_per_m = 0;            // the photo's resolution (0 = the model's)
};

struct MethodScore {
  std::string name;
  DepthMetrics metrics;
  double seconds = 0;  // total time of the method over all panels
};

// Held-out synthetic panels 0..count-1 of the series `synth` (use a seed not used in training).
std::vector<EvalPanel> SyntheticEvalPanels(const SynthOptions& synth, int count);

// Scores intensity-as-depth and Pentland SFS (both with oracle scale and offset, see
// relief_baselines.h) and, when model is not null, the model (tiled prediction).
std::vector<MethodScore> EvaluatePanels(const std::vector<EvalPanel>& panels, const DepthModel* model,
                                        const PredictOptions& predict,
                                        const ProgressCallback& progress = nullptr);

// BTS (DenseNet-161) on a visible panel, the paper's Table 2.
DepthMetrics PaperBtsMetrics();

// Fixed-width text table lines: header, and one row per method.
std::string MetricsTableHeader();
std::string MetricsTableRow(const std::string& name, const DepthMetrics& m);

}  // namespace candi::relief

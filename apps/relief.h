// `candi relief ...`: the buried-relief path (ALGORITHMS.md section 3). relief.cc declares every
// relief command (in every executable, for --help); relief_place.cc runs `place` (Ceres only, in
// candi); relief_network.cc runs the others (libtorch, in candi-relief only; handoff_stubs.cc
// stands in elsewhere).
#pragma once

#include <string>
#include <vector>

#include "apps/cli.h"
#include "pipeline/relief.h"
#include "pipeline/relief_dataset.h"
#include "reconstruction/relief/relief_metrics.h"
#include "reconstruction/relief/relief_net.h"
#include "reconstruction/relief/relief_place.h"
#include "reconstruction/relief/relief_synth.h"
#include "reconstruction/relief/relief_train.h"

namespace candi::apps {

struct ReliefSynthArgs {
  std::string output_dir;
  int count = 8;                  // panels
  relief::SynthOptions synth;     // width (pixels), metres, seed, the old-photo effects
};
int RunReliefSynth(const ReliefSynthArgs& args);

struct ReliefDatasetArgs {
  std::vector<std::string> inputs;  // scans (point files) or synthetic panels (*_photo.png, folders)
  std::string output_dir;
  pipeline::ReliefDatasetOptions options;
};
int RunReliefDataset(const ReliefDatasetArgs& args);

struct ReliefTrainArgs {
  std::vector<std::string> data_dirs;  // `relief dataset` folders, trained on together (one pair size)
  std::string output;
  bool relative = false;            // a relative model: the scale-and-shift-invariant loss
  relief::TrainOptions train;       // epochs, batch, learning rates, time budget, checkpoint, edge term, seed
  relief::NetOptions net;           // growth, decoder width (the blocks: `blocks`)
  std::string blocks = "4,6,8,6";
  std::string finetune;             // start from this model's weights (fresh optimiser)
  int threads = 1;                  // libtorch threads
};
int RunReliefTrain(const ReliefTrainArgs& args);

struct ReliefPredictArgs {
  std::string photo, model, output;
  std::string output16;             // optional 16-bit depth (levels * 256)
  pipeline::PanelDepthOptions options;
};
int RunReliefPredict(const ReliefPredictArgs& args);

struct ReliefPointsArgs {
  std::string photo, depth, output;
  relief::ReliefPointsOptions options;
};
int RunReliefPoints(const ReliefPointsArgs& args);

struct ReliefEvalArgs {
  std::vector<std::string> models;    // optional: baselines only without one
  int panels = 4;
  relief::SynthOptions synth;         // the held-out series: width, seed (1000, apart from training's)
  std::string photo, depth;           // or: one photo and its ground-truth depth
  std::vector<std::string> pairs;     // or: folders of photo pairs (relief_photo_pairs.h), each a held-out part
  relief::SurfaceMetricOptions surface;  // normals and edges (level_per_pixel, normal_step: 0 = automatic)
  double light_azimuth = -1, light_elevation = -1;  // for SFS on a photo (default: its PNG text)
  double width_m = 2.7;
  relief::PredictOptions predict;     // the tiles
  int threads = 1;
  ReliefEvalArgs() {
    synth.seed = 1000;
    surface.level_per_pixel = 0;
    surface.normal_step = 0;
  }
};
int RunReliefEval(const ReliefEvalArgs& args);

struct ReliefPlaceArgs {
  std::string correspondences, output;  // CSV panel,point,x,y,z,E,N,H[,accuracy]; placements JSON
  std::vector<std::string> panels;      // the panels' point files (<panel>.ply) or folders of them
  std::string points_out;               // folder for the panels in world coordinates
  relief::PanelPlacementOptions options;  // rigid or Sim3, robust loss, default accuracy, tolerance
};
int RunReliefPlace(const ReliefPlaceArgs& args);

}  // namespace candi::apps

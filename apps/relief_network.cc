// The relief commands that run the network or its data (candi-relief only): relief synth, dataset,
// train, predict, points, eval. Outputs are written atomically; bad inputs are InputError (exit 2).
//  - eval: the paper's Table 2 (and normal and edge metrics) for models beside intensity-as-depth,
//    linear shape from shading and the paper's BTS figures, on held-out synthetic panels, one
//    photo/depth pair, or a folder of real-photo pairs;
//  - train: one line per epoch (loss, learning rate, validation metrics) on stderr; the model and a
//    checkpoint per epoch are written atomically.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "apps/relief.h"
#include "bench/bench.h"
#include "core/check.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "core/timer.h"
#include "io/point_io.h"
#include "pipeline/relief.h"
#include "pipeline/relief_dataset.h"
#include "reconstruction/relief/relief_dataset.h"
#include "reconstruction/relief/relief_eval.h"
#include "reconstruction/relief/relief_image.h"
#include "reconstruction/relief/relief_net.h"
#include "reconstruction/relief/relief_train.h"

namespace candi::apps {

namespace {

// One photo and its ground truth; light from the options, else the PNG text, else 135/25 deg.
relief::EvalPanel PanelFromFiles(const ReliefEvalArgs& a) {
  io::PngText text;
  relief::EvalPanel p;
  p.photo = relief::ReadPhoto(a.photo, &text);
  p.depth = relief::ReadDepth(a.depth);
  if (p.photo.width() != p.depth.width() || p.photo.height() != p.depth.height()) {
    throw InputError(a.depth, "", "size differs from the photo " + a.photo);
  }
  auto from_text = [&](const char* key, double given, double fallback) {
    if (given >= 0) return given;
    return text.count(key) ? std::stod(text.at(key)) : fallback;
  };
  p.light_azimuth_deg = from_text("candi_light_azimuth_deg", a.light_azimuth, 135);
  p.light_elevation_deg = from_text("candi_light_elevation_deg", a.light_elevation, 25);
  p.pixels_per_m = a.width_m > 0 ? p.photo.width() / a.width_m : 0;
  return p;
}

}  // namespace

namespace {

// The metrics of each held-out part (a folder of photo pairs), then their mean, each part
// weighing the same.
int RunReliefEvalParts(const ReliefEvalArgs& a, const std::vector<relief::NamedModel>& named) {
  relief::SurfaceMetricOptions surface = a.surface;
  surface.level_per_pixel = a.surface.level_per_pixel > 0 ? a.surface.level_per_pixel : 1;
  surface.normal_step = a.surface.normal_step > 0 ? a.surface.normal_step : 4;
  surface.Check();
  std::vector<std::vector<relief::MethodScore>> parts;
  for (const std::string& dir : a.pairs) {
    const std::vector<relief::EvalPanel> panels = relief::PhotoEvalPanels(dir);
    ConsoleProgressOptions po;
    po.unit = "panels";
    ConsoleProgress progress("relief eval " + dir, po);
    parts.push_back(relief::EvaluatePanels(panels, named, a.predict, surface, progress.Callback()));
    progress.Finish();
    std::printf("part %zu: %zu photo pairs of %s (%lld pixels scored)\n", parts.size(), panels.size(), dir.c_str(),
                static_cast<long long>(parts.back().front().metrics.count));
    std::printf("%s\n", relief::MetricsTableHeader().c_str());
    for (const relief::MethodScore& s : parts.back()) std::printf("%s\n", relief::MetricsTableRow(s.name, s.metrics).c_str());
    std::printf("%s\n", relief::SurfaceTableHeader().c_str());
    for (const relief::MethodScore& s : parts.back()) {
      std::printf("%s\n\n", relief::SurfaceTableRow(s.name, s.normals, s.edges).c_str());
    }
  }
  const std::vector<relief::MethodScore> mean = relief::MeanOverParts(parts);
  std::printf("mean over the %zu held-out parts (each part weighs the same)\n", parts.size());
  std::printf("%s %8s\n", relief::MetricsTableHeader().c_str(), "seconds");
  for (const relief::MethodScore& s : mean) std::printf("%s %8.2f\n", relief::MetricsTableRow(s.name, s.metrics).c_str(), s.seconds);
  std::printf("%s\n", relief::SurfaceTableHeader().c_str());
  for (const relief::MethodScore& s : mean) std::printf("%s\n", relief::SurfaceTableRow(s.name, s.normals, s.edges).c_str());
  std::printf("* scale and offset fitted to the ground truth by least squares (an oracle; a relative model is scored "
              "with it, an absolute one without); "
              "levels 1..255 span each photo's 2nd..98th percentile of camera depth; normals with one level = %.4g "
              "pixel widths over %d px.\n",
              surface.level_per_pixel, surface.normal_step);
  return kOk;
}

}  // namespace

int RunReliefEval(const ReliefEvalArgs& a) {
  const relief::PredictOptions& predict = a.predict;
  predict.Check();
  if (a.photo.empty() != a.depth.empty()) throw std::invalid_argument("--photo and --depth go together");
  if (!a.pairs.empty() && !a.photo.empty()) throw std::invalid_argument("--pairs or --photo/--depth, not both");
  if (!(a.surface.level_per_pixel >= 0)) throw std::invalid_argument("--level-per-pixel must be >= 0");
  relief::SetTorchThreads(a.threads);
  std::vector<relief::DepthModel> models;
  for (const std::string& path : a.models) models.push_back(relief::DepthModel::Load(path));
  std::vector<relief::NamedModel> named;
  for (size_t k = 0; k < models.size(); ++k) {
    const std::string stem = std::filesystem::path(a.models[k]).stem().string();
    named.push_back({stem + " (" + std::to_string(models[k].ParameterCount()) + " par.)", &models[k]});
  }
  std::vector<relief::EvalPanel> panels;
  relief::SynthOptions synth = a.synth;
  relief::SurfaceMetricOptions surface = a.surface;
  double level_per_pixel = 1;  // pairs of photographs: levels are per photo, not metric
  std::string what;
  if (a.pairs.size() > 1) return RunReliefEvalParts(a, named);
  if (!a.pairs.empty()) {
    panels = relief::PhotoEvalPanels(a.pairs.front());
    what = std::to_string(panels.size()) + " photo pairs of " + a.pairs.front();
  } else if (a.photo.empty()) {
    synth.Check();
    panels = relief::SyntheticEvalPanels(synth, a.panels);
    level_per_pixel = synth.depth_m / relief::kMaxLevel / synth.PixelM();
    char line[160];
    std::snprintf(line, sizeof(line), "%d held-out synthetic panels (seed %llu, %dx%d)", a.panels,
                  static_cast<unsigned long long>(synth.seed),
                  synth.width, synth.Height());
    what = line;
  } else {
    panels.push_back(PanelFromFiles(a));
    level_per_pixel = synth.depth_m / relief::kMaxLevel / (a.width_m > 0 ? a.width_m / panels[0].photo.width() : synth.PixelM());
    what = a.photo + " against " + a.depth;
  }
  surface.level_per_pixel = a.surface.level_per_pixel > 0 ? a.surface.level_per_pixel : level_per_pixel;
  surface.normal_step = a.surface.normal_step > 0 ? a.surface.normal_step : (a.pairs.empty() ? 1 : 4);
  surface.Check();
  ConsoleProgressOptions po;
  po.unit = "panels";
  ConsoleProgress progress("relief eval", po);
  const auto scores = relief::EvaluatePanels(panels, named, predict, surface, progress.Callback());
  progress.Finish();
  std::printf("%s\n", what.c_str());
  std::printf("%s %8s\n", relief::MetricsTableHeader().c_str(), "seconds");
  std::printf("%s %8s\n", relief::MetricsTableRow("BTS DenseNet-161 (paper)", relief::PaperBtsMetrics()).c_str(), "-");
  for (const relief::MethodScore& s : scores) {
    std::printf("%s %8.2f\n", relief::MetricsTableRow(s.name, s.metrics).c_str(), s.seconds);
  }
  std::printf("\n%s\n", relief::SurfaceTableHeader().c_str());
  for (const relief::MethodScore& s : scores) {
    std::printf("%s\n", relief::SurfaceTableRow(s.name, s.normals, s.edges).c_str());
  }
  std::printf("Convention: depth levels 0..255 from the panel's front plane (255 = the wall, 1 level = "
              "depth_m / 255; for photo pairs levels 1..255 span the photo's 2nd..98th percentile of "
              "camera depth); unknown ground truth masked (%lld pixels scored); RMSE in levels.\n"
              "Normals of the height field with one level = %.4g pixel widths, differences over %d px "
              "(%lld pixels scored), "
              "angles in degrees; edges: depth steps of more than %.4g levels matched within %d px "
              "(%lld true edge pixels).\n"
              "* scale and offset fitted to the ground truth by least squares (an oracle; a relative model "
              "is scored with it, an absolute one without). The paper's row is its visible panel, not these panels.\n",
              static_cast<long long>(scores.front().metrics.count), surface.level_per_pixel, surface.normal_step,
              static_cast<long long>(scores.front().normals.count), surface.edge_jump_levels,
              surface.edge_tolerance_px, static_cast<long long>(scores.front().edges.truth));
  return kOk;
}

namespace {

// pixels_per_m from DIR/dataset.txt ("key value" lines); 0 for pairs of photographs (no metric
// resolution); throws InputError when absent or negative.
double DatasetPixelsPerM(const std::string& dir) {
  const std::string path = dir + "/dataset.txt";
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "cannot open (is this a `candi relief dataset` folder?)");
  std::string key;
  double value = 0;
  while (in >> key >> value) {
    if (key == "pixels_per_m" && value >= 0) return value;
  }
  throw InputError(path, "", "no pixels_per_m line with a value >= 0");
}

relief::NetOptions NetOptionsOf(const ReliefTrainArgs& a) {
  relief::NetOptions o = a.net;
  o.blocks.clear();
  for (double b : ParseNumbers(a.blocks, ',', "--blocks")) o.blocks.push_back(static_cast<int>(b));
  o.Check();
  return o;
}

void PrintEpoch(const relief::EpochReport& r) {
  const relief::DepthMetrics& v = r.validation;
  std::fprintf(stderr, "epoch %d/%d  loss %.4f  lr %.3g  val d1 %.4f d2 %.4f d3 %.4f rmse %.3f "
               "rmse_log %.4f abs_rel %.4f (%lld px)  %.1f s\n", r.epoch, r.epochs, r.loss,
               r.learning_rate, v.delta1, v.delta2, v.delta3, v.rmse, v.rmse_log, v.abs_rel,
               static_cast<long long>(v.count), r.seconds);
}

}  // namespace

int RunReliefTrain(const ReliefTrainArgs& a) {
  relief::TrainOptions o = a.train;
  if (o.checkpoint.empty()) o.checkpoint = a.output + ".ckpt";
  o.Check();
  relief::SetTorchThreads(a.threads);
  // The folders in order: pairs keep their folder's order, so the same folders give the same bytes.
  double ppm = 0;
  std::vector<relief::TrainingPair> train, val;
  for (const std::string& dir : a.data_dirs) {
    const double dir_ppm = DatasetPixelsPerM(dir);
    if (dir_ppm > 0 && ppm > 0 && std::abs(dir_ppm - ppm) > 1e-9 * ppm) {
      throw InputError(dir + "/dataset.txt", "", "pixels_per_m " + FormatDouble(dir_ppm) + " differs from " +
                                                    FormatDouble(ppm) + " of an earlier --data folder");
    }
    if (dir_ppm > 0) ppm = dir_ppm;
    std::vector<relief::TrainingPair> t = relief::ReadPairs(dir + "/train");
    if (t.empty()) throw InputError(dir + "/train", "", "no training pairs");
    std::vector<relief::TrainingPair> v = relief::ReadPairs(dir + "/val");
    for (const auto* set : {&t, &v}) {
      for (const relief::TrainingPair& p : *set) {
        const relief::TrainingPair& first = train.empty() ? t[0] : train[0];
        if (p.photo.width() != first.photo.width() || p.photo.height() != first.photo.height() ||
            p.photo.width() % 32 != 0 || p.photo.height() % 32 != 0) {
          throw InputError(dir, "", "pairs must share one size, a multiple of 32 (" + std::to_string(p.photo.width()) +
                                        "x" + std::to_string(p.photo.height()) + " here, " +
                                        std::to_string(first.photo.width()) + "x" +
                                        std::to_string(first.photo.height()) + " first)");
        }
      }
    }
    std::move(t.begin(), t.end(), std::back_inserter(train));
    std::move(v.begin(), v.end(), std::back_inserter(val));
  }
  // Fine-tuning starts from the given model's weights and architecture (the network options of
  // the command line do not apply) and keeps its resolution unless the data has one.
  relief::DepthModel model = a.finetune.empty() ? relief::DepthModel::Create(NetOptionsOf(a), a.train.seed)
                                                : relief::DepthModel::Load(a.finetune);
  if (ppm > 0) model.set_pixels_per_m(ppm);
  if (a.relative) model.set_relative(true);
  std::fprintf(stderr, "%s %lld parameters (%s) on %zu pairs (%zu validation), %d thread(s)\n",
               a.finetune.empty() ? "training" : ("fine-tuning " + a.finetune + ":").c_str(),
               static_cast<long long>(model.ParameterCount()),
               model.options().relative ? "relative: scale-and-shift-invariant loss" : "absolute levels", train.size(),
               val.size(), a.threads);
  const relief::TrainSummary s = relief::TrainDepthModel(o, train, val, &model, PrintEpoch);
  if (ppm > 0) model.set_pixels_per_m(ppm);
  model.Save(a.output);
  std::printf("model %s: %lld parameters, %lld steps, %.1f s%s%s\n", a.output.c_str(),
              static_cast<long long>(model.ParameterCount()), static_cast<long long>(s.steps), s.seconds,
              s.message.empty() ? "" : "; ", s.message.c_str());
  if (!s.epochs.empty()) {
    const relief::DepthMetrics& v = s.epochs.back().validation;
    std::printf("validation d1 %.4f  RMSE %.3f levels  RMSE_log %.4f\n", v.delta1, v.rmse, v.rmse_log);
  }
  return kOk;
}


int RunReliefSynth(const ReliefSynthArgs& a) {
  pipeline::WriteSyntheticPanels(a.synth, a.count, a.output_dir);
  std::printf("%d panels %dx%d (%.4g mm/pixel) in %s\n", a.count, a.synth.width, a.synth.Height(),
              1000 * a.synth.PixelM(), a.output_dir.c_str());
  return kOk;
}

int RunReliefDataset(const ReliefDatasetArgs& a) {
  const pipeline::ReliefDatasetOptions& o = a.options;
  if (!o.colmap.empty() || !o.images.empty()) {
    const pipeline::PhotoDatasetSummary s = pipeline::BuildPhotoDataset(o, a.inputs, a.output_dir);
    std::printf("%zu views (%zu held out) of %s, %.1f %% of their pixels with depth; %zu training and %zu "
                "validation patches of %dx%d in %s\n",
                s.views, s.held_out, o.colmap.c_str(), 100 * s.known_fraction, s.train, s.val, o.patches.patch,
                o.patches.patch, a.output_dir.c_str());
    if (s.empty_views > 0) std::printf("%zu view(s) without any depth\n", s.empty_views);
    if (!o.holdout_region.empty()) {
      std::printf("held-out surface %s: %llu pixels with depth in %zu view(s) of holdout/, none in training\n",
                  o.holdout_region.c_str(), static_cast<unsigned long long>(s.region_pixels), s.region_views);
    }
    return kOk;
  }
  const pipeline::ReliefDatasetSummary s = pipeline::BuildReliefDataset(o, a.inputs, a.output_dir);
  std::printf("%zu training and %zu validation pairs of %dx%d from %zu inputs in %s\n", s.train, s.val,
              o.patches.patch, o.patches.patch, s.inputs, a.output_dir.c_str());
  return kOk;
}

int RunReliefPredict(const ReliefPredictArgs& a) {
  const pipeline::PanelDepth depth = pipeline::PredictPanelDepth(a.options, a.photo, a.model);
  pipeline::WritePanelDepth(depth.depth, a.model, a.output, a.output16);
  std::printf("depth %dx%d of %s in %.2f s (%d thread(s)) -> %s\n", depth.depth.width(), depth.depth.height(),
              a.photo.c_str(), depth.seconds, a.options.threads, a.output.c_str());
  return kOk;
}

int RunReliefPoints(const ReliefPointsArgs& a) {
  a.options.Check();
  io::OutputPointFormat(a.output);  // a known extension before any work
  const Stopwatch watch;
  const pipeline::PanelPoints points = pipeline::PanelPointsOf(a.options, a.photo, a.depth);
  io::WritePointCloud(a.output, points.cloud);
  const relief::ReliefPointsOptions& o = a.options;
  std::printf("%zu points (%dx%d pixels, %.4g x %.4g x %.4g m) in %.2f s -> %s\n", points.cloud.size(), points.width,
              points.height, o.width_m, o.height_m, o.depth_m, watch.Seconds(), a.output.c_str());
  return kOk;
}

int RunBenchRelief(const bench::ReliefBenchOptions& options) { return bench::RunReliefBench(options); }

}  // namespace candi::apps

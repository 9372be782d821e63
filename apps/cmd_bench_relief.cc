// candi bench relief: accuracy costs time. For each decoder width, a BTS-style network (growth =
// width / 8, blocks 2-4-6-4) is trained for a fixed CPU budget on synthetic panels and scored on
// held-out ones beside the classical baselines; then one 3200x1024 photo is taken to 3,276,800
// metric points (predict, points, PLY write), timed.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "core/point_io.h"
#include "reconstruction/relief/relief_dataset.h"
#include "reconstruction/relief/relief_eval.h"
#include "reconstruction/relief/relief_points.h"
#include "reconstruction/relief/relief_train.h"

namespace candi::app {

namespace {

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::vector<relief::TrainingPair> TrainingPatches(const relief::SynthOptions& synth, int panels) {
  relief::PatchOptions patches;
  std::vector<relief::TrainingPair> pairs;
  for (int i = 0; i < panels; ++i) {
    relief::SynthPanel p = relief::SynthesizePanel(synth, static_cast<uint64_t>(i));
    for (auto& pair : relief::CutPatches(patches, {std::move(p.photo.photo), std::move(p.depth)})) {
      pairs.push_back(std::move(pair));
    }
  }
  return pairs;
}

// Seconds to predict one full-size photo and to turn it into points written as PLY.
void TimeFullPhoto(const relief::DepthModel& model, const relief::SynthPanel& panel, double* predict_s,
                   double* points_s) {
  relief::PredictOptions o;
  o.photo_pixels_per_m = 1.0 / panel.pixel_m;
  auto t0 = std::chrono::steady_clock::now();
  const ImageF depth = model.Predict(o, panel.photo.photo);
  *predict_s = Seconds(t0);
  t0 = std::chrono::steady_clock::now();
  const PointCloud cloud = relief::DepthToPoints({}, panel.photo.photo, depth);
  const std::string path = (std::filesystem::temp_directory_path() / "candi_bench_relief.ply").string();
  WritePointCloud(path, cloud);
  *points_s = Seconds(t0);
  std::filesystem::remove(path);
}

}  // namespace

int RunBenchRelief(const BenchReliefArgs& a) {
  if (!(a.seconds > 0)) throw std::invalid_argument("--seconds must be > 0");
  relief::SetTorchThreads(a.threads);
  relief::SynthOptions synth;
  synth.seed = a.seed;
  const std::vector<relief::TrainingPair> train = TrainingPatches(synth, a.train_panels);
  relief::SynthOptions held_out = synth;
  held_out.seed = a.seed + 1000;
  const auto panels = relief::SyntheticEvalPanels(held_out, a.eval_panels);
  relief::SynthOptions full = held_out;
  full.width = 3200;
  const relief::SynthPanel photo = relief::SynthesizePanel(full, 0);
  std::printf("Relief depth: %zu training patches 128x128 from %d synthetic panels (seed %llu), %d "
              "held-out panels (seed %llu), %d thread(s), %.0f s of training per width\n",
              train.size(), a.train_panels, a.seed, a.eval_panels, static_cast<unsigned long long>(held_out.seed), a.threads, a.seconds);
  std::printf("%s\n", relief::MetricsTableHeader().c_str());
  std::printf("%s\n", relief::MetricsTableRow("BTS DenseNet-161 (paper)", relief::PaperBtsMetrics()).c_str());
  for (const auto& s : relief::EvaluatePanels(panels, nullptr, {})) {
    std::printf("%s\n", relief::MetricsTableRow(s.name, s.metrics).c_str());
  }
  std::printf("\n%6s %6s %10s %8s %7s %8s %8s %10s %12s %12s\n", "width", "growth", "parameters",
              "train s", "steps", "d<1.25", "RMSE", "RMSE_log", "3200x1024 s", "-> points s");
  for (double w : ParseNumbers(a.widths, ',', "--widths")) {
    relief::NetOptions net;
    net.decoder_width = static_cast<int>(w);
    net.growth = std::clamp(net.decoder_width / 8, 2, 64);
    net.blocks = {2, 4, 6, 4};
    relief::DepthModel model = relief::DepthModel::Create(net, a.seed);
    model.set_pixels_per_m(1.0 / synth.PixelM());
    relief::TrainOptions o;
    o.epochs = 1000;
    o.max_seconds = a.seconds;
    o.seed = a.seed;
    const relief::TrainSummary summary = relief::TrainDepthModel(o, train, {}, &model);
    const relief::DepthMetrics m = relief::EvaluatePanels(panels, &model, {}).back().metrics;
    double predict_s = 0, points_s = 0;
    TimeFullPhoto(model, photo, &predict_s, &points_s);
    std::printf("%6d %6d %10lld %8.1f %7lld %8.4f %8.3f %10.4f %12.2f %12.2f\n", net.decoder_width,
                net.growth, static_cast<long long>(model.ParameterCount()), summary.seconds,
                static_cast<long long>(summary.steps), m.delta1, m.rmse, m.rmse_log, predict_s,
                predict_s + points_s);
    std::fflush(stdout);
  }
  std::printf("Convention: levels 0..255 from the front plane (255 = wall), RMSE in levels; * = oracle "
              "scale and offset.\n");
  return kOk;
}

}  // namespace candi::app

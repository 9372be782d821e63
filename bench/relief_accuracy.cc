// candi bench relief: accuracy costs time. For each decoder width, a BTS-style network (growth =
// width / 8, blocks 2-4-6-4) is trained for a fixed CPU budget on synthetic panels, plainly and
// with the edge term, and scored on held-out ones beside the classical baselines; then one 3200x1024 photo is taken to 3,276,800
// metric points (predict, points, PLY write), timed.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include "bench/bench.h"
#include "core/check.h"
#include "core/text_format.h"
#include "core/timer.h"
#include "io/point_io.h"
#include "reconstruction/relief/relief_dataset.h"
#include "reconstruction/relief/relief_eval.h"
#include "reconstruction/relief/relief_image.h"
#include "reconstruction/relief/relief_points.h"
#include "reconstruction/relief/relief_train.h"

namespace candi::bench {

namespace {

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
  Stopwatch watch;
  const ImageF depth = model.Predict(o, panel.photo.photo);
  *predict_s = watch.Lap();
  const PointCloud cloud = relief::DepthToPoints({}, panel.photo.photo, depth);
  const std::string path = (std::filesystem::temp_directory_path() / "candi_bench_relief.ply").string();
  io::WritePointCloud(path, cloud);
  *points_s = watch.Lap();
  std::filesystem::remove(path);
}

}  // namespace

// One held-out part of a protocol: fine-tuning pairs and the panels scored.
struct BenchPart {
  std::string dir;
  std::vector<relief::TrainingPair> train;
  std::vector<relief::EvalPanel> panels;
};

BenchPart ReadBenchPart(const std::string& dir) {
  BenchPart part;
  part.dir = dir;
  part.train = relief::ReadPairs(dir + "/train");
  if (part.train.empty()) throw InputError(dir + "/train", "", "no training pairs");
  part.panels = relief::PhotoEvalPanels(dir + "/holdout");
  return part;
}

// One protocol's table: the model as it is and fine-tuned for each budget (plain, and with the
// edge term) on each part's train/, scored on its holdout/ beside the baselines; with several
// parts, the mean over the parts (each weighing the same).
void BenchProtocol(const ReliefBenchOptions& a, const std::string& title, const std::vector<BenchPart>& parts,
                   const std::vector<double>& budgets) {
  relief::SurfaceMetricOptions surface;  // levels are per photo: one level = one pixel width
  surface.normal_step = 4;                 // as `relief eval --pairs`: the dense cloud is noisy at 1 px
  std::printf("\n%s\n", title.c_str());
  for (const BenchPart& p : parts) {
    std::printf("  %s: %zu fine-tuning patches, %zu held-out photos\n", p.dir.c_str(), p.train.size(), p.panels.size());
  }
  std::printf("%-30s %9s %7s %8s %8s %8s %8s %7s %8s\n", "method", "tune s", "steps", "d<1.25",
              "RMSE", "RMSE_log", "normal", "<22.5", "edge F1");
  auto row = [](const std::string& name, double seconds, int64_t steps, const relief::MethodScore& s) {
    std::printf("%-30s %9.1f %7lld %8.4f %8.3f %8.4f %8.2f %7.4f %8.4f\n", name.c_str(), seconds,
                static_cast<long long>(steps), s.metrics.delta1, s.metrics.rmse, s.metrics.rmse_log,
                s.normals.mean_deg, s.normals.within_22, s.edges.f1);
    std::fflush(stdout);
  };
  auto part_rows = [&](const std::vector<std::vector<relief::MethodScore>>& scores, double seconds, int64_t steps) {
    if (scores.size() > 1) {
      for (size_t k = 0; k < scores.size(); ++k) {
        for (const auto& s : scores[k]) row("  " + s.name + " [" + std::to_string(k + 1) + "]", seconds, steps, s);
      }
    }
    for (const auto& s : relief::MeanOverParts(scores)) row(s.name, seconds, steps, s);
  };
  const relief::DepthModel base = relief::DepthModel::Load(a.model);
  std::vector<std::vector<relief::MethodScore>> first;
  for (const BenchPart& p : parts) first.push_back(relief::EvaluatePanels(p.panels, {{"as shipped", &base}}, {}, surface));
  part_rows(first, 0, 0);
  if (a.relative && !base.options().relative) {
    // The same weights read as a relative model: whole images, scored after the fit.
    relief::DepthModel as_relative = relief::DepthModel::Load(a.model);
    as_relative.set_relative(true);
    std::vector<std::vector<relief::MethodScore>> rel;
    for (const BenchPart& p : parts) {
      rel.push_back(relief::EvaluatePanels(p.panels, {{"as shipped, read as relative", &as_relative}}, {}, surface));
      rel.back().erase(rel.back().begin(), rel.back().end() - 1);
    }
    part_rows(rel, 0, 0);
  }
  std::vector<double> weights = {0};
  if (a.edge_weight > 0) weights.push_back(a.edge_weight);
  for (double budget : budgets) {
    for (double w : weights) {
      std::string name = w > 0 ? "fine-tuned, edge term " + FormatDouble(w) : "fine-tuned";
      std::vector<std::vector<relief::MethodScore>> scores;
      double seconds = 0;
      int64_t steps = 0;
      for (const BenchPart& p : parts) {
        relief::DepthModel model = relief::DepthModel::Load(a.model);
        if (a.relative) model.set_relative(true);
        relief::TrainOptions o;
        o.epochs = 1000;
        o.max_seconds = budget;
        o.learning_rate = a.learning_rate;
        o.end_learning_rate = a.learning_rate / 10;
        o.edge_weight = w;
        o.seed = a.seed;
        const relief::TrainSummary summary = relief::TrainDepthModel(o, p.train, {}, &model);
        seconds += summary.seconds / parts.size();
        steps += summary.steps;
        // An absolute model predicts in tiles of its training patches (context matters on a
        // photograph); a relative one whole images.
        relief::PredictOptions tuned;
        tuned.tiles.tile = p.train.front().photo.width();
        tuned.tiles.overlap = tuned.tiles.tile / 4;
        tuned.Check();
        scores.push_back(relief::EvaluatePanels(p.panels, {{name, &model}}, tuned, surface));
      }
      // The baselines were rows already: only the model's row.
      for (auto& part : scores) part.erase(part.begin(), part.end() - 1);
      part_rows(scores, seconds, steps / static_cast<int64_t>(parts.size()));
    }
  }
}

// Real photos: the held-out photo protocol (--pairs) and the held-out surface one (--parts),
// each its own table, so that the gap between a new viewpoint and a new surface shows.
int BenchReliefPhotos(const ReliefBenchOptions& a) {
  const std::vector<double> budgets = ParseNumbers(a.finetune_seconds, ',', "--finetune-seconds");
  for (double b : budgets) {
    if (!(b > 0)) throw std::invalid_argument("--finetune-seconds: budgets must be > 0");
  }
  std::printf("Relief depth on real photos: %d thread(s), fine-tuning %s%s (lr %.3g, seed %llu)\n", a.threads,
              a.model.c_str(), a.relative ? " into a relative model" : "", a.learning_rate,
              static_cast<unsigned long long>(a.seed));
  if (!a.pairs.empty()) {
    BenchProtocol(a, "Protocol: held-out photos (new viewpoints of the surfaces fine-tuned on)",
                  {ReadBenchPart(a.pairs)}, budgets);
  }
  if (!a.parts.empty()) {
    std::vector<BenchPart> parts;
    for (const std::string& dir : a.parts) parts.push_back(ReadBenchPart(dir));
    BenchProtocol(a, "Protocol: held-out surfaces (each part in turn masked out of fine-tuning, then scored alone; "
                     "then the mean over the parts)", parts, budgets);
  }
  std::printf("Levels 1..255 span each photo's 2nd..98th percentile of camera depth; normals with one "
              "level = one pixel width, differences over 4 px; * = least-squares scale and offset fitted to the "
              "ground truth (the baselines and relative models; absolute models are scored as they predict). "
              "Fine-tuning seconds and steps are per part. The poly decay runs over 1000 epochs, so a budget "
              "stops it early at a near-constant learning rate.\n");
  return 0;
}

void ReliefBenchOptions::Check() const {
  CANDI_CHECK_OPTION(seconds > 0, seconds, "> 0");
  CANDI_CHECK_OPTION_IN(train_panels, 1, 10000);
  CANDI_CHECK_OPTION_IN(eval_panels, 1, 10000);
  CANDI_CHECK_OPTION_IN(threads, 1, 256);
  CANDI_CHECK_OPTION_IN(edge_weight, 0.0, 1000.0);
  CANDI_CHECK_OPTION(learning_rate > 0, learning_rate, "> 0");
}

int RunReliefBench(const ReliefBenchOptions& a) {
  a.Check();
  relief::SetTorchThreads(a.threads);
  if (!a.pairs.empty() || !a.parts.empty()) return BenchReliefPhotos(a);
  if (!(a.seconds > 0)) throw std::invalid_argument("--seconds must be > 0");
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
              train.size(), a.train_panels, static_cast<unsigned long long>(a.seed), a.eval_panels, static_cast<unsigned long long>(held_out.seed), a.threads, a.seconds);
  std::printf("%s\n", relief::MetricsTableHeader().c_str());
  std::printf("%s\n", relief::MetricsTableRow("BTS DenseNet-161 (paper)", relief::PaperBtsMetrics()).c_str());
  relief::SurfaceMetricOptions surface;
  surface.level_per_pixel = synth.depth_m / relief::kMaxLevel / synth.PixelM();
  for (const auto& s : relief::EvaluatePanels(panels, {}, {}, surface)) {
    std::printf("%s  normal %.2f deg\n", relief::MetricsTableRow(s.name, s.metrics).c_str(), s.normals.mean_deg);
  }
  std::printf("\n%6s %6s %5s %10s %8s %7s %8s %8s %10s %8s %7s %12s %12s\n", "width", "growth", "edge",
              "parameters", "train s", "steps", "d<1.25", "RMSE", "RMSE_log", "normal", "edge F1",
              "3200x1024 s", "-> points s");
  std::vector<double> weights = {0};
  if (a.edge_weight > 0) weights.push_back(a.edge_weight);
  for (double w : ParseNumbers(a.widths, ',', "--widths")) {
    for (double edge : weights) {
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
      o.edge_weight = edge;
      const relief::TrainSummary summary = relief::TrainDepthModel(o, train, {}, &model);
      const relief::MethodScore score = relief::EvaluatePanels(panels, {{"candi", &model}}, {}, surface).back();
      const relief::DepthMetrics& m = score.metrics;
      double predict_s = 0, points_s = 0;
      TimeFullPhoto(model, photo, &predict_s, &points_s);
      std::printf("%6d %6d %5.2g %10lld %8.1f %7lld %8.4f %8.3f %10.4f %8.2f %7.4f %12.2f %12.2f\n",
                  net.decoder_width, net.growth, edge, static_cast<long long>(model.ParameterCount()),
                  summary.seconds, static_cast<long long>(summary.steps), m.delta1, m.rmse, m.rmse_log,
                  score.normals.mean_deg, score.edges.f1, predict_s, predict_s + points_s);
      std::fflush(stdout);
    }
  }
  std::printf("Convention: levels 0..255 from the front plane (255 = wall), RMSE in levels; * = oracle "
              "scale and offset.\n");
  return 0;
}

}  // namespace candi::bench

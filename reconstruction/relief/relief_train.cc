#include "reconstruction/relief/relief_train.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/rng.h"
#include "reconstruction/relief/relief_baselines.h"
#include "reconstruction/relief/relief_image.h"
#include "reconstruction/relief/relief_net_internal.h"

namespace candi::relief {

namespace {

torch::Tensor DepthBatch(const std::vector<const ImageF*>& depths) {
  const int w = depths[0]->width(), h = depths[0]->height();
  torch::Tensor t = torch::empty({static_cast<int64_t>(depths.size()), 1, h, w});
  float* out = t.data_ptr<float>();
  for (const ImageF* d : depths) {
    for (float v : d->values()) *out++ = std::isfinite(v) ? v : 0.0f;
  }
  return t;
}

// BTS: lr = (lr0 - lr_end) (1 - step / total)^power + lr_end.
double PolyLearningRate(const TrainOptions& o, int64_t step, int64_t total) {
  const double f = std::max(0.0, 1.0 - static_cast<double>(step) / std::max<int64_t>(total, 1));
  return (o.learning_rate - o.end_learning_rate) * std::pow(f, o.decay_power) + o.end_learning_rate;
}

void SetLearningRate(torch::optim::Adam* opt, double lr) {
  for (auto& group : opt->param_groups()) static_cast<torch::optim::AdamOptions&>(group.options()).lr(lr);
}

std::vector<size_t> Shuffled(size_t n, uint64_t seed, int epoch) {
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  Rng rng(HashIndex(seed, static_cast<uint64_t>(epoch), 41));
  for (size_t i = n; i > 1; --i) std::swap(order[i - 1], order[rng.Below(i)]);
  return order;
}

struct Progress {
  int epoch = 0;     // completed epochs
  int64_t step = 0;  // optimiser steps
};

void SaveCheckpoint(const std::string& path, const DepthModel& model, torch::optim::Adam& opt,
                    const Progress& p) {
  torch::serialize::OutputArchive archive, optimizer;
  WriteModelArchive(model.impl(), &archive);
  opt.save(optimizer);
  archive.write("optimizer", optimizer);
  archive.write("epoch", torch::tensor(static_cast<int64_t>(p.epoch)));
  archive.write("step", torch::tensor(p.step));
  SaveArchive(archive, path);
}

// Loads weights into *model (same architecture) and returns the archive for the optimiser.
Progress LoadCheckpoint(const std::string& path, DepthModel* model, torch::serialize::InputArchive* archive) {
  const std::string bytes = ReadFileToString(path);
  Progress p;
  try {
    std::istringstream in(bytes);
    archive->load_from(in);
    auto loaded = ReadModelArchive(*archive);
    const NetOptions &a = loaded->net->options, &b = model->options();
    if (a.growth != b.growth || a.blocks != b.blocks || a.decoder_width != b.decoder_width) {
      throw InputError(path, "", "checkpoint network options differ from the requested ones");
    }
    model->impl().net = loaded->net;
    p.epoch = static_cast<int>(ReadTensor(*archive, "epoch").item<int64_t>());
    p.step = ReadTensor(*archive, "step").item<int64_t>();
  } catch (const c10::Error& e) {
    throw InputError(path, "", std::string("not a candi relief checkpoint: ") + e.what_without_backtrace());
  }
  return p;
}

// The edge term: mean |d log p - d log g| over horizontal and vertical neighbour pairs 1, 2 and 4
// pixels apart whose ground truth is known at both ends (a gradient-matching loss, as in
// MegaDepth): it rewards depth steps at the true places, which the scale-invariant log loss,
// a sum over single pixels, cannot see. x10 like the SI-log loss.
torch::Tensor EdgeLoss(const torch::Tensor& pred, const torch::Tensor& gt, const torch::Tensor& mask) {
  const torch::Tensor lp = torch::log(pred);
  const torch::Tensor lg = torch::log(torch::clamp_min(gt, kMinValidLevel));
  const torch::Tensor m = mask.to(torch::kFloat);
  torch::Tensor sum = pred.sum() * 0.0, count = torch::zeros({});
  for (int64_t dim : {2, 3}) {
    for (int64_t step : {1, 2, 4}) {
      const int64_t n = pred.size(dim) - step;
      if (n <= 0) continue;
      const torch::Tensor dp = lp.narrow(dim, step, n) - lp.narrow(dim, 0, n);
      const torch::Tensor dg = lg.narrow(dim, step, n) - lg.narrow(dim, 0, n);
      const torch::Tensor both = m.narrow(dim, step, n) * m.narrow(dim, 0, n);
      sum = sum + ((dp - dg).abs() * both).sum();
      count = count + both.sum();
    }
  }
  return sum / torch::clamp_min(count, 1.0) * 10.0;
}

// Absolute models: the SI-log loss. Relative ones: the scale-and-shift-invariant loss, and the
// edge term on the aligned prediction (its log differences do not depend on the offset).
torch::Tensor TrainingLoss(const TrainOptions& o, bool relative, const torch::Tensor& pred, const torch::Tensor& gt) {
  const torch::Tensor mask = gt >= kMinValidLevel;
  if (relative) {
    torch::Tensor loss = ScaleShiftInvariantLoss(pred, gt, mask);
    if (o.edge_weight > 0) {
      const torch::Tensor aligned = torch::clamp(AlignScaleShift(pred, gt, mask), kMinValidLevel, kMaxLevel);
      loss = loss + o.edge_weight * EdgeLoss(aligned, gt, mask);
    }
    return loss;
  }
  torch::Tensor loss = SilogLoss(pred, gt, mask);
  if (o.edge_weight > 0) loss = loss + o.edge_weight * EdgeLoss(pred, gt, mask);
  return loss;
}

// A relative model is scored after the least-squares scale and offset, as `relief eval` does.
DepthMetrics Validate(const DepthModel& model, const std::vector<TrainingPair>& pairs) {
  DepthMetricsAccumulator acc;
  for (const TrainingPair& p : pairs) {
    const ImageF prediction = model.PredictTile(p.photo);
    acc.Add(model.options().relative ? FitLevels(prediction, p.depth) : prediction, p.depth);
  }
  return acc.Result();
}

}  // namespace

void TrainOptions::Check() const {
  CANDI_CHECK_OPTION_GE(epochs, 1);
  CANDI_CHECK_OPTION_GE(batch, 1);
  CANDI_CHECK_OPTION_GT(learning_rate, 0);
  CANDI_CHECK_OPTION_IN(end_learning_rate, 0, learning_rate);
  CANDI_CHECK_OPTION_GT(decay_power, 0);
  CANDI_CHECK_OPTION_GE(max_seconds, 0);
  CANDI_CHECK_OPTION_MSG(!resume || !checkpoint.empty(), resume, "needs a checkpoint path");
  CANDI_CHECK_OPTION(edge_weight >= 0 && std::isfinite(edge_weight), edge_weight, ">= 0");
  augment.Check();
}

double EvaluateLoss(const DepthModel& model, const std::vector<TrainingPair>& pairs) {
  torch::NoGradGuard no_grad;
  model.impl().net->eval();
  double sum = 0;
  for (const TrainingPair& p : pairs) {
    const torch::Tensor gt = DepthBatch({&p.depth});
    const torch::Tensor pred = model.impl().net->forward(PhotoBatch({&p.photo}));
    sum += (model.options().relative ? ScaleShiftInvariantLoss(pred, gt, gt >= kMinValidLevel)
                                     : SilogLoss(pred, gt, gt >= kMinValidLevel)).item<double>();
  }
  return pairs.empty() ? 0.0 : sum / pairs.size();
}

TrainSummary TrainDepthModel(const TrainOptions& o, const std::vector<TrainingPair>& train,
                             const std::vector<TrainingPair>& validation, DepthModel* model,
                             const EpochCallback& on_epoch) {
  o.Check();
  CANDI_CHECK(model != nullptr && !train.empty());
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  Progress progress;
  torch::serialize::InputArchive resumed;
  const bool resuming = o.resume && std::filesystem::exists(o.checkpoint);
  if (resuming) progress = LoadCheckpoint(o.checkpoint, model, &resumed);
  BtsNet& net = model->impl().net;
  torch::optim::Adam opt(net->parameters(), torch::optim::AdamOptions(o.learning_rate).eps(1e-6));
  if (resuming) {
    torch::serialize::InputArchive optimizer;
    resumed.read("optimizer", optimizer);
    opt.load(optimizer);
    LogInfo("resumed from " + o.checkpoint + " after epoch " + std::to_string(progress.epoch));
  }
  const int64_t per_epoch = (static_cast<int64_t>(train.size()) + o.batch - 1) / o.batch;
  const int64_t total = per_epoch * o.epochs;
  TrainSummary summary;
  for (int epoch = progress.epoch; epoch < o.epochs && !summary.stopped_early; ++epoch) {
    net->train();
    const std::vector<size_t> order = Shuffled(train.size(), o.seed, epoch);
    double loss_sum = 0;
    int64_t batches = 0;
    for (int64_t s = 0; s < per_epoch; ++s) {
      SetLearningRate(&opt, PolyLearningRate(o, progress.step, total));
      std::vector<TrainingPair> batch;
      for (size_t k = s * o.batch; k < std::min(train.size(), static_cast<size_t>((s + 1) * o.batch)); ++k) {
        batch.push_back(Augment(o.augment, train[order[k]], o.seed, epoch * train.size() + k));
      }
      std::vector<const ImageF*> photos, depths;
      for (const TrainingPair& p : batch) photos.push_back(&p.photo), depths.push_back(&p.depth);
      const torch::Tensor gt = DepthBatch(depths);
      const torch::Tensor loss = TrainingLoss(o, model->options().relative, net->forward(PhotoBatch(photos)), gt);
      opt.zero_grad();
      loss.backward();
      opt.step();
      ++progress.step;
      loss_sum += loss.item<double>();
      ++batches;
      if (o.max_seconds > 0 && elapsed() > o.max_seconds) summary.stopped_early = true;
      if (summary.stopped_early) break;
    }
    if (!summary.stopped_early) progress.epoch = epoch + 1;
    EpochReport report;
    report.epoch = epoch + 1;
    report.epochs = o.epochs;
    report.loss = loss_sum / std::max<int64_t>(batches, 1);
    report.learning_rate = PolyLearningRate(o, progress.step, total);
    report.validation = Validate(*model, validation);
    report.seconds = elapsed();
    if (!o.checkpoint.empty()) SaveCheckpoint(o.checkpoint, *model, opt, progress);
    summary.epochs.push_back(report);
    if (on_epoch) on_epoch(report);
  }
  summary.steps = progress.step;
  summary.seconds = elapsed();
  if (summary.stopped_early) {
    summary.message = "stopped after " + std::to_string(summary.seconds) + " s (max_seconds), in epoch " +
                      std::to_string(summary.epochs.empty() ? 0 : summary.epochs.back().epoch);
  }
  return summary;
}

}  // namespace candi::relief

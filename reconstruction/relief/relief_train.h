// Training the relief network on (photo, depth) pairs.
//
// Adam (lr -> end_lr by polynomial decay, power 0.9, as BTS), scale-invariant log loss with the
// "no data" pixels masked (with edge_weight > 0 plus an edge term: the mean error of log-depth
// differences 1, 2 and 4 pixels apart, edge guidance as a loss); a relative model
// (NetOptions::relative) instead gets the scale-and-shift-invariant loss (each image's
// prediction fitted to its ground truth by least squares first, then the RMSE of log levels),
// and its edge term is taken on the fitted prediction, and its validation scored after the fit; the paper's augmentation drawn
// per (seed, epoch, sample), batches in a seeded shuffled order. After each epoch: the validation
// metrics (relief_metrics.h) and, with a checkpoint path, a checkpoint (weights, optimiser state,
// epoch) written atomically; `resume` continues from it. Fine-tuning is training a loaded model
// (DepthModel::Load) with a fresh optimiser. Deterministic for a seed and thread count (libtorch's
// float sums may differ in the last bits between thread counts). Running out of time
// (`max_seconds`) is a result in the summary, not an error.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "reconstruction/relief/relief_dataset.h"
#include "reconstruction/relief/relief_metrics.h"
#include "reconstruction/relief/relief_net.h"

namespace candi::relief {

struct TrainOptions {
  int epochs = 10;            // passes over the training pairs, >= 1
  int batch = 8;              // pairs per step, >= 1
  double learning_rate = 1e-3;      // start (from scratch; the paper's 1e-4 assumes pretraining), > 0
  double end_learning_rate = 1e-4;  // end of the polynomial decay, [0, learning_rate]
  double decay_power = 0.9;   // polynomial decay power, > 0
  AugmentOptions augment;
  uint64_t seed = 1;          // shuffling and augmentation
  std::string checkpoint;     // path written after every epoch ("" = none)
  bool resume = false;        // continue from `checkpoint` when it exists
  double max_seconds = 0;     // stop after the step that passes this many seconds (0 = no limit)
  double edge_weight = 0;     // weight of the edge (depth-gradient matching) loss term, >= 0; 0 = off
  void Check() const;
};

struct EpochReport {
  int epoch = 0;               // 1-based
  int epochs = 0;
  double loss = 0;             // mean training loss of the epoch
  double learning_rate = 0;    // at the end of the epoch
  DepthMetrics validation;     // on the validation pairs (count 0 when there are none)
  double seconds = 0;          // since training started (this run)
};

struct TrainSummary {
  std::vector<EpochReport> epochs;
  int64_t steps = 0;           // optimiser steps in total (with resumed ones)
  double seconds = 0;          // this run
  bool stopped_early = false;  // max_seconds reached
  std::string message;
};

using EpochCallback = std::function<void(const EpochReport&)>;

// Trains *model in place. train must not be empty; all pairs share one size (a multiple of 32).
TrainSummary TrainDepthModel(const TrainOptions& options, const std::vector<TrainingPair>& train,
                             const std::vector<TrainingPair>& validation, DepthModel* model,
                             const EpochCallback& on_epoch = nullptr);

// Mean scale-invariant log loss of the model on pairs (eval mode, no augmentation).
double EvaluateLoss(const DepthModel& model, const std::vector<TrainingPair>& pairs);

}  // namespace candi::relief

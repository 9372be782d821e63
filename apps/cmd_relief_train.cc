// candi relief train: trains the relief depth network on a `candi relief dataset` folder; one
// line per epoch (loss, learning rate, validation metrics) on stderr; the model and a checkpoint
// per epoch are written atomically.
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "core/check.h"
#include "reconstruction/relief/relief_dataset.h"
#include "reconstruction/relief/relief_net.h"
#include "reconstruction/relief/relief_train.h"

namespace candi::app {

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
  relief::NetOptions o;
  o.growth = a.growth;
  o.decoder_width = a.decoder_width;
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
  relief::TrainOptions o;
  o.epochs = a.epochs;
  o.batch = a.batch;
  o.learning_rate = a.learning_rate;
  o.end_learning_rate = a.end_learning_rate;
  o.max_seconds = a.max_seconds;
  o.seed = a.seed;
  o.checkpoint = a.checkpoint.empty() ? a.output + ".ckpt" : a.checkpoint;
  o.resume = a.resume;
  o.edge_weight = a.edge_weight;
  o.Check();
  relief::SetTorchThreads(a.threads);
  const double ppm = DatasetPixelsPerM(a.data_dir);
  const std::vector<relief::TrainingPair> train = relief::ReadPairs(a.data_dir + "/train");
  const std::vector<relief::TrainingPair> val = relief::ReadPairs(a.data_dir + "/val");
  if (train.empty()) throw InputError(a.data_dir + "/train", "", "no training pairs");
  for (const auto* set : {&train, &val}) {
    for (const relief::TrainingPair& p : *set) {
      if (p.photo.width() != train[0].photo.width() || p.photo.height() != train[0].photo.height() ||
          p.photo.width() % 32 != 0 || p.photo.height() % 32 != 0) {
        throw InputError(a.data_dir, "", "pairs must share one size, a multiple of 32");
      }
    }
  }
  // Fine-tuning starts from the given model's weights and architecture (the network options of
  // the command line do not apply) and keeps its resolution unless the data has one.
  relief::DepthModel model = a.finetune.empty() ? relief::DepthModel::Create(NetOptionsOf(a), a.seed)
                                                : relief::DepthModel::Load(a.finetune);
  if (ppm > 0) model.set_pixels_per_m(ppm);
  std::fprintf(stderr, "%s %lld parameters on %zu pairs (%zu validation), %d thread(s)\n",
               a.finetune.empty() ? "training" : ("fine-tuning " + a.finetune + ":").c_str(),
               static_cast<long long>(model.ParameterCount()), train.size(), val.size(), a.threads);
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

}  // namespace candi::app

// candi relief eval: the paper's Table 2 for a model beside intensity-as-depth, linear shape
// from shading and the paper's BTS figures, on held-out synthetic panels or one photo/depth pair.
#include <cstdio>
#include <optional>
#include <string>

#include "apps/commands.h"
#include "core/check.h"
#include "core/progress.h"
#include "reconstruction/relief/relief_eval.h"
#include "reconstruction/relief/relief_image.h"

namespace candi::app {

namespace {

// One photo and its ground truth; light from the options, else the PNG text, else 135/25 deg.
relief::EvalPanel PanelFromFiles(const ReliefEvalArgs& a) {
  PngText text;
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

int RunReliefEval(const ReliefEvalArgs& a) {
  relief::PredictOptions predict;
  predict.tiles.tile = a.tile;
  predict.tiles.overlap = a.overlap;
  predict.Check();
  if (a.photo.empty() != a.depth.empty()) throw std::invalid_argument("--photo and --depth go together");
  relief::SetTorchThreads(a.threads);
  std::optional<relief::DepthModel> model;
  if (!a.model.empty()) model = relief::DepthModel::Load(a.model);
  std::vector<relief::EvalPanel> panels;
  relief::SynthOptions synth;
  synth.width = a.width;
  synth.seed = a.seed;
  if (a.photo.empty()) {
    synth.Check();
    panels = relief::SyntheticEvalPanels(synth, a.panels);
  } else {
    panels.push_back(PanelFromFiles(a));
  }
  ConsoleProgressOptions po;
  po.unit = "panels";
  ConsoleProgress progress("relief eval", po);
  const auto scores = relief::EvaluatePanels(panels, model ? &*model : nullptr, predict, progress.Callback());
  progress.Finish();
  if (a.photo.empty()) {
    std::printf("%d held-out synthetic panels (seed %llu, %dx%d)\n", a.panels, a.seed, synth.width, synth.Height());
  } else {
    std::printf("%s against %s\n", a.photo.c_str(), a.depth.c_str());
  }
  std::printf("%s %8s\n", relief::MetricsTableHeader().c_str(), "seconds");
  std::printf("%s %8s\n", relief::MetricsTableRow("BTS DenseNet-161 (paper)", relief::PaperBtsMetrics()).c_str(), "-");
  for (const relief::MethodScore& s : scores) {
    const std::string name = s.name == "candi BTS" ? "candi BTS (" + std::to_string(model->ParameterCount()) + " par.)" : s.name;
    std::printf("%s %8.2f\n", relief::MetricsTableRow(name, s.metrics).c_str(), s.seconds);
  }
  std::printf("Convention: depth levels 0..255 from the panel's front plane (255 = the wall, 1 level = "
              "depth_m / 255); ground truth below level 1 masked (%lld pixels scored); RMSE in levels.\n"
              "* scale and offset fitted to the ground truth by least squares (an oracle the network "
              "does not get). The paper's row is its visible panel, not these panels.\n",
              static_cast<long long>(scores.front().metrics.count));
  return kOk;
}

}  // namespace candi::app

// candi relief eval: the paper's Table 2 (and normal and edge metrics) for models beside
// intensity-as-depth, linear shape from shading and the paper's BTS figures, on held-out synthetic
// panels, one photo/depth pair, or a folder of real-photo pairs.
#include <cstdio>
#include <filesystem>
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

int RunReliefEval(const ReliefEvalArgs& a) {
  relief::PredictOptions predict;
  predict.tiles.tile = a.tile;
  predict.tiles.overlap = a.overlap;
  predict.Check();
  if (a.photo.empty() != a.depth.empty()) throw std::invalid_argument("--photo and --depth go together");
  if (!a.pairs.empty() && !a.photo.empty()) throw std::invalid_argument("--pairs or --photo/--depth, not both");
  if (!(a.level_per_pixel >= 0)) throw std::invalid_argument("--level-per-pixel must be >= 0");
  relief::SetTorchThreads(a.threads);
  std::vector<relief::DepthModel> models;
  for (const std::string& path : a.models) models.push_back(relief::DepthModel::Load(path));
  std::vector<relief::NamedModel> named;
  for (size_t k = 0; k < models.size(); ++k) {
    const std::string stem = std::filesystem::path(a.models[k]).stem().string();
    named.push_back({stem + " (" + std::to_string(models[k].ParameterCount()) + " par.)", &models[k]});
  }
  std::vector<relief::EvalPanel> panels;
  relief::SynthOptions synth;
  synth.width = a.width;
  synth.seed = a.seed;
  relief::SurfaceMetricOptions surface;
  surface.edge_jump_levels = a.edge_jump;
  surface.edge_tolerance_px = a.edge_tolerance;
  double level_per_pixel = 1;  // pairs of photographs: levels are per photo, not metric
  std::string what;
  if (!a.pairs.empty()) {
    panels = relief::PhotoEvalPanels(a.pairs);
    what = std::to_string(panels.size()) + " photo pairs of " + a.pairs;
  } else if (a.photo.empty()) {
    synth.Check();
    panels = relief::SyntheticEvalPanels(synth, a.panels);
    level_per_pixel = synth.depth_m / relief::kMaxLevel / synth.PixelM();
    char line[160];
    std::snprintf(line, sizeof(line), "%d held-out synthetic panels (seed %llu, %dx%d)", a.panels, a.seed,
                  synth.width, synth.Height());
    what = line;
  } else {
    panels.push_back(PanelFromFiles(a));
    level_per_pixel = synth.depth_m / relief::kMaxLevel / (a.width_m > 0 ? a.width_m / panels[0].photo.width() : synth.PixelM());
    what = a.photo + " against " + a.depth;
  }
  surface.level_per_pixel = a.level_per_pixel > 0 ? a.level_per_pixel : level_per_pixel;
  surface.normal_step = a.normal_step > 0 ? a.normal_step : (a.pairs.empty() ? 1 : 4);
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
              "* scale and offset fitted to the ground truth by least squares (an oracle the network "
              "does not get). The paper's row is its visible panel, not these panels.\n",
              static_cast<long long>(scores.front().metrics.count), surface.level_per_pixel, surface.normal_step,
              static_cast<long long>(scores.front().normals.count), surface.edge_jump_levels,
              surface.edge_tolerance_px, static_cast<long long>(scores.front().edges.truth));
  return kOk;
}

}  // namespace candi::app

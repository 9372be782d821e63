#include "reconstruction/relief/relief_eval.h"

#include <chrono>
#include <cstdio>

#include "reconstruction/relief/relief_baselines.h"

namespace candi::relief {

namespace {

double Since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

std::vector<EvalPanel> SyntheticEvalPanels(const SynthOptions& synth, int count) {
  std::vector<EvalPanel> panels;
  for (int i = 0; i < count; ++i) {
    SynthPanel p = SynthesizePanel(synth, static_cast<uint64_t>(i));
    EvalPanel e;
    e.photo = std::move(p.photo.photo);
    e.depth = std::move(p.depth);
    e.light_azimuth_deg = p.photo.light_azimuth_deg;
    e.light_elevation_deg = p.photo.light_elevation_deg;
    e.pixels_per_m = 1.0 / p.pixel_m;
    panels.push_back(std::move(e));
  }
  return panels;
}

std::vector<MethodScore> EvaluatePanels(const std::vector<EvalPanel>& panels, const DepthModel* model,
                                        const PredictOptions& predict, const ProgressCallback& progress) {
  DepthMetricsAccumulator intensity, sfs, net;
  double t_intensity = 0, t_sfs = 0, t_net = 0;
  uint64_t done = 0;
  for (const EvalPanel& p : panels) {
    auto t0 = std::chrono::steady_clock::now();
    intensity.Add(FitLevels(IntensityAsHeight(p.photo), p.depth), p.depth);
    t_intensity += Since(t0);
    t0 = std::chrono::steady_clock::now();
    sfs.Add(FitLevels(PentlandHeight(p.photo, p.light_azimuth_deg, p.light_elevation_deg), p.depth), p.depth);
    t_sfs += Since(t0);
    if (model != nullptr) {
      t0 = std::chrono::steady_clock::now();
      PredictOptions o = predict;
      o.photo_pixels_per_m = p.pixels_per_m;
      net.Add(model->Predict(o, p.photo), p.depth);
      t_net += Since(t0);
    }
    if (progress) progress(++done, panels.size());
  }
  std::vector<MethodScore> scores = {{"intensity as depth*", intensity.Result(), t_intensity},
                                     {"linear SFS, Pentland*", sfs.Result(), t_sfs}};
  if (model != nullptr) scores.push_back({"candi BTS", net.Result(), t_net});
  return scores;
}

DepthMetrics PaperBtsMetrics() {
  DepthMetrics m;
  m.delta1 = 0.4406, m.delta2 = 0.7700, m.delta3 = 0.9206;
  m.rmse = 9.84, m.rmse_log = 0.455, m.abs_rel = 4.07, m.sq_rel = 2.13;
  return m;
}

std::string MetricsTableHeader() {
  char line[160];
  std::snprintf(line, sizeof(line), "%-26s %7s %7s %7s %8s %8s %8s %8s", "method", "d<1.25",
                "d<1.25^2", "d<1.25^3", "RMSE", "RMSE_log", "abs_rel", "sq_rel");
  return line;
}

std::string MetricsTableRow(const std::string& name, const DepthMetrics& m) {
  char line[200];
  std::snprintf(line, sizeof(line), "%-26s %7.4f %8.4f %8.4f %8.3f %8.4f %8.4f %8.4f", name.c_str(),
                m.delta1, m.delta2, m.delta3, m.rmse, m.rmse_log, m.abs_rel, m.sq_rel);
  return line;
}

}  // namespace candi::relief

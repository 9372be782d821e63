#include "reconstruction/relief/relief_eval.h"

#include <chrono>
#include <cstdio>
#include <stdexcept>

#include "core/check.h"
#include "reconstruction/relief/relief_baselines.h"
#include "reconstruction/relief/relief_photo_pairs.h"

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

std::vector<EvalPanel> PhotoEvalPanels(const std::string& dir) {
  std::vector<EvalPanel> panels;
  for (PhotoPair& pair : ReadPhotoPairs(dir)) {
    EvalPanel e;
    e.name = dir + "/" + pair.name;
    e.photo = std::move(pair.photo);
    e.depth = std::move(pair.depth);
    e.mask = std::move(pair.mask);
    panels.push_back(std::move(e));
  }
  return panels;
}

std::vector<MethodScore> EvaluatePanels(const std::vector<EvalPanel>& panels,
                                        const std::vector<NamedModel>& models,
                                        const PredictOptions& predict,
                                        const SurfaceMetricOptions& surface,
                                        const ProgressCallback& progress) {
  struct Method {
    Method(std::string name, const SurfaceMetricOptions& surface) : shape(surface) {
      score.name = std::move(name);
    }
    MethodScore score;
    DepthMetricsAccumulator depth;
    SurfaceMetricsAccumulator shape;
  };
  std::vector<Method> methods;
  methods.emplace_back("intensity as depth*", surface);
  methods.emplace_back("linear SFS, Pentland*", surface);
  for (const NamedModel& m : models) {
    CANDI_CHECK(m.model != nullptr) << m.name;
    methods.emplace_back(m.model->options().relative ? m.name + "*" : m.name, surface);
  }
  auto score = [](Method* m, const ImageF& prediction, const EvalPanel& p, double seconds) {
    m->depth.Add(prediction, p.depth, p.mask);
    m->shape.Add(prediction, p.depth, p.mask);
    m->score.seconds += seconds;
  };
  uint64_t done = 0;
  for (const EvalPanel& p : panels) {
    // The oracle fits of the baselines use only the pixels that are scored.
    ImageF fit_truth = p.depth;
    if (!p.mask.empty()) {
      for (size_t i = 0; i < fit_truth.values().size(); ++i) {
        if (p.mask.values()[i] == 0) fit_truth.values()[i] = 0;
      }
    }
    auto t0 = std::chrono::steady_clock::now();
    ImageF prediction = FitLevels(IntensityAsHeight(p.photo), fit_truth);
    score(&methods[0], prediction, p, Since(t0));
    t0 = std::chrono::steady_clock::now();
    prediction = FitLevels(PentlandHeight(p.photo, p.light_azimuth_deg, p.light_elevation_deg), fit_truth);
    score(&methods[1], prediction, p, Since(t0));
    for (size_t k = 0; k < models.size(); ++k) {
      t0 = std::chrono::steady_clock::now();
      PredictOptions o = predict;
      o.photo_pixels_per_m = p.pixels_per_m;
      o.stretch = false;
      prediction = models[k].model->Predict(o, p.photo);
      // A relative model gets the baselines' least-squares scale and offset; an absolute one not.
      if (models[k].model->options().relative) prediction = FitLevels(prediction, fit_truth);
      score(&methods[2 + k], prediction, p, Since(t0));
    }
    if (progress) progress(++done, panels.size());
  }
  std::vector<MethodScore> scores;
  for (Method& m : methods) {
    m.score.metrics = m.depth.Result();
    m.score.normals = m.shape.Normals();
    m.score.edges = m.shape.Edges();
    scores.push_back(std::move(m.score));
  }
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
  std::snprintf(line, sizeof(line), "%-28s %7s %7s %7s %8s %8s %8s %8s", "method", "d<1.25",
                "d<1.25^2", "d<1.25^3", "RMSE", "RMSE_log", "abs_rel", "sq_rel");
  return line;
}

std::string SurfaceTableHeader() {
  char line[160];
  std::snprintf(line, sizeof(line), "%-28s %8s %8s %7s %7s %7s %8s %8s %8s", "method", "normal",
                "median", "<11.25", "<22.5", "<30", "edge P", "edge R", "edge F1");
  return line;
}

std::vector<MethodScore> MeanOverParts(const std::vector<std::vector<MethodScore>>& parts) {
  if (parts.empty()) throw std::invalid_argument("MeanOverParts: no parts");
  std::vector<MethodScore> mean = parts.front();
  for (size_t m = 0; m < mean.size(); ++m) {
    MethodScore& out = mean[m];
    out.metrics = DepthMetrics();
    out.normals = NormalMetrics();
    out.edges = EdgeMetrics();
    out.seconds = 0;
    int depth_parts = 0, normal_parts = 0, edge_parts = 0;
    for (const std::vector<MethodScore>& part : parts) {
      if (part.size() != mean.size() || part[m].name != out.name) {
        throw std::invalid_argument("MeanOverParts: the parts score different methods");
      }
      const MethodScore& s = part[m];
      out.seconds += s.seconds;
      if (s.metrics.count > 0) {
        ++depth_parts;
        DepthMetrics& d = out.metrics;
        d.delta1 += s.metrics.delta1, d.delta2 += s.metrics.delta2, d.delta3 += s.metrics.delta3;
        d.rmse += s.metrics.rmse, d.rmse_log += s.metrics.rmse_log;
        d.abs_rel += s.metrics.abs_rel, d.sq_rel += s.metrics.sq_rel;
        d.count += s.metrics.count;
      }
      if (s.normals.count > 0) {
        ++normal_parts;
        NormalMetrics& n = out.normals;
        n.mean_deg += s.normals.mean_deg, n.median_deg += s.normals.median_deg;
        n.within_11 += s.normals.within_11, n.within_22 += s.normals.within_22, n.within_30 += s.normals.within_30;
        n.count += s.normals.count;
      }
      if (s.edges.truth > 0) {
        ++edge_parts;
        EdgeMetrics& e = out.edges;
        e.precision += s.edges.precision, e.recall += s.edges.recall, e.f1 += s.edges.f1;
        e.predicted += s.edges.predicted, e.truth += s.edges.truth;
      }
    }
    const auto divide = [](double* v, int k) { *v = k > 0 ? *v / k : 0.0; };
    DepthMetrics& d = out.metrics;
    for (double* v : {&d.delta1, &d.delta2, &d.delta3, &d.rmse, &d.rmse_log, &d.abs_rel, &d.sq_rel}) divide(v, depth_parts);
    NormalMetrics& n = out.normals;
    for (double* v : {&n.mean_deg, &n.median_deg, &n.within_11, &n.within_22, &n.within_30}) divide(v, normal_parts);
    EdgeMetrics& e = out.edges;
    for (double* v : {&e.precision, &e.recall, &e.f1}) divide(v, edge_parts);
  }
  return mean;
}

std::string SurfaceTableRow(const std::string& name, const NormalMetrics& n, const EdgeMetrics& e) {
  char line[200];
  std::snprintf(line, sizeof(line), "%-28s %8.2f %8.2f %7.4f %7.4f %7.4f %8.4f %8.4f %8.4f",
                name.c_str(), n.mean_deg, n.median_deg, n.within_11, n.within_22, n.within_30,
                e.precision, e.recall, e.f1);
  return line;
}

std::string MetricsTableRow(const std::string& name, const DepthMetrics& m) {
  char line[200];
  std::snprintf(line, sizeof(line), "%-28s %7.4f %8.4f %8.4f %8.3f %8.4f %8.4f %8.4f", name.c_str(),
                m.delta1, m.delta2, m.delta3, m.rmse, m.rmse_log, m.abs_rel, m.sq_rel);
  return line;
}

}  // namespace candi::relief

#include "pipeline/compare.h"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/text_format.h"
#include "io/mesh_io.h"
#include "io/point_io.h"

namespace candi::pipeline {

namespace {

// A number for JSON: NaN and infinity as null.
nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

std::string Settings(const CompareOptions& o, const compare::DeviationResult& r) {
  using compare::Method;
  switch (o.deviation.method) {
    case Method::kC2C:
      return o.deviation.c2c.local_model == compare::LocalModel::kNone
                 ? "nearest reference point"
                 : "local " + compare::LocalModelName(o.deviation.c2c.local_model) + " over " +
                       std::to_string(o.deviation.c2c.model_neighbours) + " neighbours";
    case Method::kC2M:
      return o.deviation.c2m.signed_distance ? "signed distance to the mesh"
                                             : "unsigned distance to the mesh";
    case Method::kM3C2:
      return "normal scale D " + FormatSignificant(r.normal_scale, 5) + " m, projection scale d " +
             FormatSignificant(r.projection_scale, 5) + " m, max depth " +
             FormatSignificant(r.max_depth, 5) + " m, registration error " +
             FormatSignificant(o.deviation.m3c2.registration_error, 5) + " m, normals towards " +
             compare::NormalOrientationName(o.deviation.m3c2.orientation);
  }
  return "";
}

std::string FileName(const std::string& path) {
  return std::filesystem::path(path).filename().string();
}

}  // namespace

void CompareOptions::Check() const {
  deviation.Check();
  summary.Check();
}

std::string CompareSummaryJson(const CompareOptions& options, const CompareOutcome& outcome,
                               const std::string& reference, const std::string& compared) {
  const compare::DeviationSummary& s = outcome.summary;
  const compare::DeviationResult& r = outcome.result;
  nlohmann::ordered_json j;
  j["reference"] = reference;
  j["compared"] = compared;
  j["method"] = compare::MethodName(s.method);
  j["settings"] = Settings(options, r);
  j["signed"] = s.is_signed;
  j["count"] = s.count;
  j["defined"] = s.defined;
  j["undefined"] = s.undefined;
  j["mean_m"] = Number(s.mean);
  j["std_m"] = Number(s.std);
  j["rms_m"] = Number(s.rms);
  j["mean_abs_m"] = Number(s.mean_abs);
  j["min_m"] = Number(s.min);
  j["max_m"] = Number(s.max);
  nlohmann::ordered_json percentiles = nlohmann::ordered_json::object();
  for (const auto& [p, v] : s.percentiles) percentiles["p" + FormatSignificant(p, 3)] = Number(v);
  j["percentiles_m"] = percentiles;
  j["tolerance_m"] = s.tolerance;
  j["within_tolerance"] = Number(s.defined ? s.within_tolerance : NAN);
  if (s.method == compare::Method::kM3C2) {
    j["significant"] = s.significant;
    j["no_normal"] = r.no_normal;
    j["too_few_points"] = r.too_few_points;
    j["normal_scale_m"] = r.normal_scale;
    j["projection_scale_m"] = r.projection_scale;
    j["max_depth_m"] = r.max_depth;
    j["registration_error_m"] = options.deviation.m3c2.registration_error;
  }
  if (s.method == compare::Method::kC2C) j["model_fallbacks"] = r.model_fallbacks;
  j["histogram"] = {{"min_m", s.histogram_min}, {"max_m", s.histogram_max}, {"bins", s.bins},
                    {"below", s.below}, {"above", s.above}};
  j["warnings"] = r.warnings;
  j["files"] = {{"cloud", FileName(outcome.cloud)}, {"histogram", FileName(outcome.histogram)},
                {"report", FileName(outcome.report)}};
  return j.dump(2) + "\n";
}

CompareOutcome RunCompare(const CompareOptions& options, const std::string& reference,
                          const std::string& compared, const std::string& output,
                          const ProgressCallback& progress) {
  options.Check();
  io::PointReadOptions read;
  read.columns = options.columns;
  const PointCloud compared_cloud = io::ReadPointCloud(compared, read);
  CompareOutcome out;
  if (options.deviation.method == compare::Method::kC2M) {
    const TriMesh mesh = io::ReadMesh(reference);
    out.result = compare::CompareToMesh(options.deviation, mesh, compared_cloud, reference,
                                        compared, progress);
  } else {
    const PointCloud reference_cloud = io::ReadPointCloud(reference, read);
    out.result = compare::CompareToCloud(options.deviation, reference_cloud, compared_cloud,
                                         reference, compared, progress);
  }
  out.summary = compare::Summarize(out.result, options.summary);
  out.cloud = output;
  out.json = output + ".compare.json";
  out.histogram = output + ".histogram.svg";
  out.report = output + ".report.md";
  io::WritePointCloud(output, compare::WithDeviationFields(compared_cloud, out.result));
  const std::string title = compare::MethodName(out.summary.method) + ": " + FileName(compared) +
                            " against " + FileName(reference);
  WriteFileAtomic(out.histogram, compare::HistogramSvg(out.summary, title));
  compare::ReportContext context;
  context.reference = reference;
  context.compared = compared;
  context.settings = Settings(options, out.result);
  context.histogram_file = FileName(out.histogram);
  context.output_file = FileName(out.cloud);
  context.warnings = out.result.warnings;
  WriteFileAtomic(out.report, compare::ReportMarkdown(out.summary, context));
  WriteFileAtomic(out.json, CompareSummaryJson(options, out, reference, compared));
  return out;
}

}  // namespace candi::pipeline

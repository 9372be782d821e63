// candi georef IN --targets targets.csv -o OUT: fits a robust similarity from model to survey
// coordinates on the control targets (reconstruction/photogrammetry/georef.h), prints the
// per-target residuals and the RMSE of control and check targets, writes IN transformed (in double,
// in the targets' integer shift) and OUT.georef.json (the transform and the report).
// Chunks processed separately are tied into one frame by running this per chunk with the same
// targets: every chunk lands in the survey frame, with the same shift.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/commands.h"
#include "apps/output_folder.h"
#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "io/crs.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/georef.h"
#include "reconstruction/photogrammetry/georef_colmap.h"

namespace candi::app {

namespace {

namespace pg = candi::photogrammetry;
using nlohmann::json;

constexpr size_t kChunk = 1 << 20;

pg::SimilarityFitOptions Options(const GeorefArgs& a) {
  pg::SimilarityFitOptions o;
  o.loss = pg::ParseRobustLoss(a.loss);
  o.loss_scale = a.loss_scale;
  o.outlier_threshold = a.outlier_threshold;
  o.estimate_scale = !a.rigid;
  if (!(a.loss_scale > 0)) throw std::invalid_argument("--loss-scale must be > 0 m");
  if (!(a.outlier_threshold >= 0)) throw std::invalid_argument("--outlier-threshold must be >= 0 m");
  o.Check();
  return o;
}

std::string Fixed(double v, int digits = 4) {
  if (!std::isfinite(v)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

std::string Status(const pg::GeorefResult& r, size_t i) {
  if (!r.targets[i].unused_reason.empty()) return "unused: " + r.targets[i].unused_reason;
  return r.outlier[i] ? "OUTLIER" : "ok";
}

void PrintReport(const pg::GeorefResult& r) {
  std::printf("%-12s %-7s %9s %9s %9s %9s %9s %9s %5s  %s\n", "target", "role", "dX m", "dY m",
              "dZ m", "dXY m", "d3D m", "reproj px", "views", "status");
  for (size_t i = 0; i < r.targets.size(); ++i) {
    const pg::SurveyTarget& t = r.targets[i];
    const Eigen::Vector3d& d = r.residuals[i];
    const bool used = t.unused_reason.empty();
    std::printf("%-12s %-7s %9s %9s %9s %9s %9s %9s %5d  %s\n", t.name.c_str(),
                pg::TargetRoleName(t.role).c_str(), used ? Fixed(d.x()).c_str() : "-",
                used ? Fixed(d.y()).c_str() : "-", used ? Fixed(d.z()).c_str() : "-",
                used ? Fixed(d.head<2>().norm()).c_str() : "-", used ? Fixed(d.norm()).c_str() : "-",
                Fixed(t.reprojection_px, 2).c_str(), t.views, Status(r, i).c_str());
  }
  std::printf("\n%-26s %5s %9s %9s %9s %9s %9s\n", "RMSE", "n", "X m", "Y m", "Z m", "XY m", "3D m");
  const std::pair<const char*, const pg::Rmse*> rows[] = {
      {"control (outliers out)", &r.control}, {"check", &r.check}};
  for (const auto& [name, e] : rows) {
    std::printf("%-26s %5d %9s %9s %9s %9s %9s\n", name, e->count, Fixed(e->x).c_str(),
                Fixed(e->y).c_str(), Fixed(e->z).c_str(), Fixed(e->xy).c_str(), Fixed(e->d3).c_str());
  }
  const Sim3& t = r.survey_from_model;
  std::printf("\nscale %.9f, rotation %.6f deg, shift %s, outlier threshold %.4f m, %s\n", t.scale,
              Eigen::AngleAxisd(t.rotation).angle() * 180 / M_PI, r.frame.ToString().c_str(),
              r.fit.threshold, r.fit.converged ? "converged" : "NOT CONVERGED");
  std::printf("layout: collinearity s2/s1 %.3g, planarity s3/s1 %.3g\n", r.fit.collinearity,
              r.fit.planarity);
  for (const std::string& w : r.fit.warnings) std::printf("warning: %s\n", w.c_str());
}

json Vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

json RmseJson(const pg::Rmse& e) {
  return {{"count", e.count}, {"x", e.x}, {"y", e.y}, {"z", e.z}, {"xy", e.xy}, {"3d", e.d3}};
}

json ReportJson(const GeorefArgs& a, const pg::GeorefResult& r) {
  const Sim3& t = r.survey_from_model;
  json j;
  const Eigen::Matrix3d rot = t.rotation.toRotationMatrix();
  j["survey_from_model"] = {
      {"scale", t.scale},
      {"rotation", {Vec(rot.row(0)), Vec(rot.row(1)), Vec(rot.row(2))}},
      {"quaternion_wxyz", {t.rotation.w(), t.rotation.x(), t.rotation.y(), t.rotation.z()}},
      {"translation", Vec(t.translation)}};
  j["shift"] = Vec(r.frame.origin);
  j["local_translation"] = Vec(t.translation - r.frame.origin);  // survey - shift = s R x + this
  j["loss"] = a.loss;
  j["loss_scale"] = a.loss_scale;
  if (!a.crs.empty()) j["crs"] = a.crs;
  if (!a.targets_crs.empty()) j["targets_crs"] = a.targets_crs;
  j["outlier_threshold"] = r.fit.threshold;
  j["converged"] = r.fit.converged;
  j["solver"] = r.fit.solver_message;
  j["collinearity"] = r.fit.collinearity;
  j["planarity"] = r.fit.planarity;
  j["warnings"] = r.fit.warnings;
  j["targets"] = json::array();
  for (size_t i = 0; i < r.targets.size(); ++i) {
    const pg::SurveyTarget& s = r.targets[i];
    const Eigen::Vector3d& d = r.residuals[i];
    json row = {{"name", s.name}, {"role", pg::TargetRoleName(s.role)}, {"status", Status(r, i)}};
    if (s.unused_reason.empty()) {
      row.update({{"dx", d.x()}, {"dy", d.y()}, {"dz", d.z()}, {"dxy", d.head<2>().norm()},
                  {"d3d", d.norm()}, {"outlier", static_cast<bool>(r.outlier[i])}});
    }
    if (std::isfinite(s.reprojection_px)) row.update({{"reprojection_px", s.reprojection_px}, {"views", s.views}});
    j["targets"].push_back(row);
  }
  j["rmse"] = {{"control", RmseJson(r.control)}, {"check", RmseJson(r.check)}};
  return j;
}

// GNSS or national-grid targets into the survey CRS, with PROJ.
void TransformTargets(const GeorefArgs& a, std::vector<pg::SurveyTarget>* targets) {
  if (a.crs.empty()) throw std::invalid_argument("--targets-crs needs --crs (the CRS to fit in)");
  const io::CrsTransform transform(a.targets_crs, a.crs, a.targets);
  LogInfo("targets: " + io::CrsLabel(a.targets_crs) + " -> " + io::CrsLabel(a.crs) + " (" + transform.operation() + ")");
  for (pg::SurveyTarget& t : *targets) {
    t.survey = transform.Apply(t.survey);
    if (!t.survey.allFinite()) {
      throw InputError(a.targets, "line " + std::to_string(t.line),
                       "target '" + t.name + "' lies outside " + io::CrsLabel(a.crs) + "'s domain (PROJ cannot transform it)");
    }
  }
}

void TransformPointFile(const GeorefArgs& a, const pg::GeorefResult& r) {
  auto reader = io::OpenPointReader(a.input);
  io::PointWriteSpec spec;
  spec.schema = reader->info().schema;
  spec.meta = reader->info().meta;
  if (!a.crs.empty()) spec.meta.crs = a.crs;
  spec.frame = r.frame;
  spec.count = reader->info().count;
  auto writer = io::OpenPointWriter(a.output, spec);
  PointCloud chunk;
  while (reader->Read(kChunk, &chunk) > 0) {
    pg::ApplySimilarity(r.survey_from_model, r.frame, &chunk);
    writer->Write(chunk);
  }
  writer->Close();
  LogInfo("wrote " + std::to_string(writer->points_written()) + " points to " + a.output);
}

void TransformModel(const GeorefArgs& a, const pg::GeorefResult& r, PointCloud points) {
  std::filesystem::create_directories(a.output);
  const Sim3 local_from_model(r.survey_from_model.scale, r.survey_from_model.rotation,
                              r.survey_from_model.translation - r.frame.origin);
  pg::WriteGeoreferencedColmapModel(a.input, local_from_model, a.output);
  pg::ApplySimilarity(r.survey_from_model, r.frame, &points);
  io::WritePointCloud(a.output + "/points.ply", points);
}

}  // namespace

int RunGeoref(const GeorefArgs& args) {
  const pg::SimilarityFitOptions options = Options(args);  // bad values: exit 1
  const bool input_is_model = std::filesystem::is_directory(args.input);
  if (!input_is_model) {
    io::DetectPointFormat(args.input);   // readable and known, before the work
    io::OutputPointFormat(args.output);
  }
  CheckOutputFolder(args.output);
  std::vector<pg::SurveyTarget> targets = pg::ReadSurveyTargets(args.targets);
  if (!args.targets_crs.empty()) TransformTargets(args, &targets);
  const std::string model_dir = input_is_model ? args.input : args.model;
  pg::ColmapGeorefInput model;
  if (!model_dir.empty()) model = pg::ReadColmapForGeoref(model_dir);
  if (!args.picks.empty()) {
    if (model_dir.empty()) {
      throw std::invalid_argument("--picks needs the cameras: --model SPARSE_DIR or a model as IN");
    }
    const int skipped = pg::TriangulateTargets(pg::ReadImagePicks(args.picks), args.picks,
                                               model.cameras, &targets);
    if (skipped > 0) {
      LogWarning(std::to_string(skipped) + " picks name images this model does not have; skipped");
    }
  }
  const pg::GeorefResult result = pg::Georeference(options, targets, args.targets);
  PrintReport(result);
  for (const std::string& w : result.fit.warnings) LogWarning(w);
  if (input_is_model) {
    TransformModel(args, result, model.points);
  } else {
    TransformPointFile(args, result);
  }
  WriteFileAtomic(args.output + ".georef.json", ReportJson(args, result).dump(2) + "\n");
  return kOk;  // a fit that did not converge is reported (table, JSON, warning), not an error
}

}  // namespace candi::app

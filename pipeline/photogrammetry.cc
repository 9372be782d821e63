#include "pipeline/photogrammetry.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/timer.h"
#include "io/crs.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/mvs/dense_workspace.h"

namespace candi::pipeline {

namespace {

namespace pg = photogrammetry;
using nlohmann::json;

// The stages on stderr, a line each when they start and end and every few seconds between, with
// how much is done and, from that, the time left in the stage.
void PrintSfmProgress(const std::string& stage, int index, int count, double seconds, bool done, double fraction) {
  if (done) {
    std::fprintf(stderr, "[sfm %d/%d] %s done in %.1f s\n", index, count, stage.c_str(), seconds);
  } else if (seconds == 0) {
    std::fprintf(stderr, "[sfm %d/%d] %s ...\n", index, count, stage.c_str());
  } else if (fraction > 0) {
    std::fprintf(stderr, "[sfm %d/%d] %s running, %.0f s, %.0f %% (about %.0f s left)\n", index, count,
                 stage.c_str(), seconds, 100 * fraction, seconds * (1 - fraction) / fraction);
  } else {
    std::fprintf(stderr, "[sfm %d/%d] %s running, %.0f s\n", index, count, stage.c_str(), seconds);
  }
}

json SfmReport(const pg::SfmSummary& s, const pg::SfmOptions& o) {
  json j;
  j["colmap_version"] = s.colmap.version;
  j["cuda"] = s.colmap.cuda;
  j["images_total"] = s.images.size();
  j["images_registered"] = s.registered.size();
  j["registered"] = s.registered;
  j["ignored_files"] = s.ignored;
  j["images_without_exif"] = s.no_exif;
  j["images_unreadable"] = s.unreadable;
  j["images_other_size"] = s.other_size;
  json duplicates = json::array();
  for (const auto& [copy, kept] : s.duplicates) duplicates.push_back({{"left_out", copy}, {"same_as", kept}});
  j["images_duplicate"] = duplicates;
  j["default_focal_px"] = s.default_focal_px;
  j["points"] = s.points;
  j["mean_reprojection_error_px"] = s.mean_reprojection_error;
  j["mean_track_length"] = s.mean_track_length;
  j["matcher"] = "candi exact brute force, " + s.matcher;
  j["pairs_matched"] = s.pairs_tried;
  j["pairs_verified"] = s.pairs_verified;
  if (!s.chunked.chunks.empty()) {
    json chunks = json::array();
    for (const pg::ChunkResult& k : s.chunked.chunks) {
      chunks.push_back({{"name", k.name}, {"photos", k.images}, {"registered", k.registered}, {"points", k.points},
                        {"tied", k.tied}, {"reason", k.reason}, {"control_targets", k.control_used},
                        {"check_targets", k.check_used}, {"control_rmse_m", k.control.d3},
                        {"check_rmse_m", k.check.d3}, {"unused_targets", k.unused_targets}});
    }
    json pairs = json::array();
    for (const pg::ChunkPairConsistency& p : s.chunked.pairs) {
      pairs.push_back({{"a", p.a}, {"b", p.b}, {"overlap_points", p.overlap}, {"median_m", p.median}, {"p90_m", p.p90}});
    }
    const pg::JointAdjustmentResult& ja = s.chunked.joint;
    j["joint_adjustment"] = {{"ran", ja.ran},
                             {"reason", ja.reason},
                             {"links", ja.links},
                             {"observations_added", ja.extended},
                             {"links_refused", ja.links_rejected},
                             {"joined_points", ja.joined_points},
                             {"observations", ja.observations},
                             {"reprojection_rms_before_px", ja.rms_before_px},
                             {"reprojection_rms_after_px", ja.rms_after_px},
                             {"control_rmse_m", ja.control.d3},
                             {"check_rmse_m", ja.check.d3},
                             {"check_targets", ja.check.count},
                             {"iterations", ja.iterations},
                             {"converged", ja.converged},
                             {"seconds", ja.seconds}};
    j["chunks"] = chunks;
    j["chunk_consistency"] = pairs;
    j["shift"] = {s.chunked.frame.origin.x(), s.chunked.frame.origin.y(), s.chunked.frame.origin.z()};
  }
  j["reproducibility"] = kSfmReproducibility;
  j["max_image_size"] = o.max_image_size;
  j["max_features"] = o.max_features;
  j["model_dir"] = s.model_dir;
  j["dense_dir"] = s.dense_dir;
  json stages = json::object();
  for (const auto& [stage, seconds] : s.stage_seconds) stages[stage] = seconds;
  j["stage_seconds"] = stages;
  return j;
}

json Vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

json RmseJson(const pg::Rmse& e) {
  return {{"count", e.count}, {"x", e.x}, {"y", e.y}, {"z", e.z}, {"xy", e.xy}, {"3d", e.d3}};
}

std::string TargetStatus(const pg::GeorefResult& r, size_t i) {
  if (!r.targets[i].unused_reason.empty()) return "unused: " + r.targets[i].unused_reason;
  return r.outlier[i] ? "OUTLIER" : "ok";
}

// GNSS or national-grid targets into the survey CRS, with PROJ.
void TransformTargets(const GeorefOptions& o, const std::string& targets_csv, std::vector<pg::SurveyTarget>* targets) {
  if (o.crs.empty()) throw std::invalid_argument("--targets-crs needs --crs (the CRS to fit in)");
  const io::CrsTransform transform(o.targets_crs, o.crs, targets_csv);
  LogInfo("targets: " + io::CrsLabel(o.targets_crs) + " -> " + io::CrsLabel(o.crs) + " (" + transform.operation() +
          ")");
  for (pg::SurveyTarget& t : *targets) {
    t.survey = transform.Apply(t.survey);
    if (!t.survey.allFinite()) {
      throw InputError(targets_csv, "line " + std::to_string(t.line),
                       "target '" + t.name + "' lies outside " + io::CrsLabel(o.crs) +
                           "'s domain (PROJ cannot transform it)");
    }
  }
}

}  // namespace

pg::SfmSummary StructureFromMotion(const pg::SfmOptions& options, const std::string& images,
                                   const std::string& workspace, const pg::ChunkMapperRunner& run_mappers) {
  const pg::SfmSummary s = pg::RunSfm(options, images, workspace, PrintSfmProgress, run_mappers);
  if (!s.no_exif.empty()) {
    LogWarning(std::to_string(s.no_exif.size()) + " photo(s) without an EXIF focal length (e.g. " + s.no_exif.front() +
               "): COLMAP started from a guessed focal of " + std::to_string(static_cast<int>(s.default_focal_px)) +
               " px (1.2 x the longest side)" + (options.single_camera ? ", refined as one shared camera" : ""));
  }
  if (s.registered.size() < s.images.size()) {
    LogWarning(std::to_string(s.images.size() - s.registered.size()) + " photo(s) not registered");
  }
  const std::string report = (std::filesystem::path(workspace) / "sfm_report.json").string();
  WriteFileAtomic(report, SfmReport(s, options).dump(2) + "\n");
  return s;
}

void DenseOptions::Check() const {
  stereo.Check();
  fusion.Check();
}

std::string DenseComment(const std::string& workspace) { return "candi dense " + workspace; }

DenseCloud DenseStereo(const DenseOptions& options, const std::string& workspace, const DenseRankShare& share) {
  options.Check();
  pg::DenseStreamOptions o;
  o.stereo = options.stereo;
  o.fusion = options.fusion;
  o.max_memory = options.max_memory;
  o.keep_maps = options.write_maps;
  o.rank = share.rank;
  o.ranks = share.ranks;
  o.all_gather = share.all_gather;
  o.cells_out = share.cells_out;
  DenseCloud out = pg::RunDenseStream(o, workspace);
  if (share.rank != 0) return out;
  out.cloud.meta.comments.push_back(DenseComment(workspace));
  if (out.points == 0) LogWarning("dense: no points (textureless images, no overlap, or too strict filters)");
  return out;
}

void GeorefOptions::Check() const { fit.Check(); }

pg::GeorefResult FitGeoref(const GeorefOptions& options, const std::string& targets_csv,
                           const pg::ColmapGeorefInput* model, const std::string& picks_csv) {
  options.Check();
  std::vector<pg::SurveyTarget> targets = pg::ReadSurveyTargets(targets_csv);
  if (!options.targets_crs.empty()) TransformTargets(options, targets_csv, &targets);
  if (!picks_csv.empty()) {
    if (model == nullptr) throw std::invalid_argument("--picks needs the cameras: --model SPARSE_DIR or a model as IN");
    const int skipped = pg::TriangulateTargets(pg::ReadImagePicks(picks_csv), picks_csv, model->cameras, &targets);
    if (skipped > 0) LogWarning(std::to_string(skipped) + " picks name images this model does not have; skipped");
  }
  return pg::Georeference(options.fit, targets, targets_csv);
}

void Georeference(const GeorefOptions& options, const pg::GeorefResult& result, PointCloud* cloud) {
  pg::ApplySimilarity(result.survey_from_model, result.frame, cloud);
  if (!options.crs.empty()) cloud->meta.crs = options.crs;
}

json GeorefReport(const GeorefOptions& o, const pg::GeorefResult& r) {
  const Sim3& t = r.survey_from_model;
  json j;
  const Eigen::Matrix3d rot = t.rotation.toRotationMatrix();
  j["survey_from_model"] = {{"scale", t.scale},
                            {"rotation", {Vec(rot.row(0)), Vec(rot.row(1)), Vec(rot.row(2))}},
                            {"quaternion_wxyz", {t.rotation.w(), t.rotation.x(), t.rotation.y(), t.rotation.z()}},
                            {"translation", Vec(t.translation)}};
  j["shift"] = Vec(r.frame.origin);
  j["local_translation"] = Vec(t.translation - r.frame.origin);  // survey - shift = s R x + this
  j["loss"] = pg::RobustLossName(o.fit.loss);
  j["loss_scale"] = o.fit.loss_scale;
  if (!o.crs.empty()) j["crs"] = o.crs;
  if (!o.targets_crs.empty()) j["targets_crs"] = o.targets_crs;
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
    json row = {{"name", s.name}, {"role", pg::TargetRoleName(s.role)}, {"status", TargetStatus(r, i)}};
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

namespace {

// IN, a point file, streamed through the transform into OUT.
void GeoreferencePointFile(const GeorefOptions& o, const GeorefFiles& files, const pg::GeorefResult& r) {
  auto reader = io::OpenPointReader(files.input);
  io::PointWriteSpec spec;
  spec.schema = reader->info().schema;
  spec.meta = reader->info().meta;
  if (!o.crs.empty()) spec.meta.crs = o.crs;
  spec.frame = r.frame;
  spec.count = reader->info().count;
  auto writer = io::OpenPointWriter(files.output, spec);
  PointCloud chunk;
  while (reader->Read(1 << 20, &chunk) > 0) {
    pg::ApplySimilarity(r.survey_from_model, r.frame, &chunk);
    writer->Write(chunk);
  }
  writer->Close();
  LogInfo("wrote " + std::to_string(writer->points_written()) + " points to " + files.output);
}

// IN, a COLMAP model, moved into OUT (a model folder) with its points.
void GeoreferenceModel(const GeorefFiles& files, const pg::GeorefResult& r, PointCloud points) {
  std::filesystem::create_directories(files.output);
  const Sim3 local_from_model(r.survey_from_model.scale, r.survey_from_model.rotation,
                              r.survey_from_model.translation - r.frame.origin);
  pg::WriteGeoreferencedColmapModel(files.input, local_from_model, files.output);
  pg::ApplySimilarity(r.survey_from_model, r.frame, &points);
  io::WritePointCloud(files.output + "/points.ply", points);
}

}  // namespace

pg::GeorefResult GeoreferenceFiles(const GeorefOptions& options, const GeorefFiles& files,
                                   const std::function<void(const pg::GeorefResult&)>& fitted) {
  options.Check();  // bad values: exit 1
  const bool input_is_model = std::filesystem::is_directory(files.input);
  if (!input_is_model) {
    io::DetectPointFormat(files.input);  // readable and known, before the work
    io::OutputPointFormat(files.output);
  }
  CheckOutputFolder(files.output);
  const std::string model_dir = input_is_model ? files.input : files.model;
  pg::ColmapGeorefInput model;
  if (!model_dir.empty()) model = pg::ReadColmapForGeoref(model_dir);
  const pg::GeorefResult result =
      FitGeoref(options, files.targets, model_dir.empty() ? nullptr : &model, files.picks);
  if (fitted) fitted(result);
  for (const std::string& w : result.fit.warnings) LogWarning(w);
  if (input_is_model) {
    GeoreferenceModel(files, result, model.points);
  } else {
    GeoreferencePointFile(options, files, result);
  }
  WriteFileAtomic(files.output + ".georef.json", GeorefReport(options, result).dump(2) + "\n");
  return result;
}

}  // namespace candi::pipeline

// How a build digitizes each kind of layer (pipeline/build.h): a point file is read; a foundation
// is built from its drawing (pipeline/foundation.h); relief panels go through the depth network
// (a ReliefPanelRunner) and are placed by Ceres; photogrammetry runs structure from motion and
// dense stereo as the layer asks, then georeferences (pipeline/photogrammetry.h). Each stage's own
// outputs stay in work/ as the commands would write them.
#include <cstdlib>
#include <filesystem>
#include <map>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "io/layer_clouds.h"
#include "io/point_io.h"
#include "pipeline/build_internal.h"
#include "pipeline/foundation.h"
#include "pipeline/photogrammetry.h"
#include "reconstruction/photogrammetry/sfm/colmap_runner.h"
#include "reconstruction/relief/relief_place.h"

namespace candi::pipeline {

namespace {

namespace fs = std::filesystem;
using internal::LayerResult;
using nlohmann::json;

// This executable's sibling `name` (candi-relief for the relief stages).
std::string Sibling(const std::string& name) {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? name : (self.parent_path() / name).string();
}

void RunChild(const std::vector<std::string>& argv, const std::string& log, const std::string& what) {
  const int code = photogrammetry::RunLogged(argv, log);
  if (code != 0) {
    throw InputError(log, "", what + " failed (exit code " + std::to_string(code) + "): " +
                                  photogrammetry::TailOfFile(log, 10));
  }
}

LayerResult Foundation(const BuildOptions& options, const Scene& scene, const SceneLayer& l, const std::string& work) {
  FoundationPointsOptions f = l.foundation;
  f.sample.seed = scene.seed;
  f.sample.threads = options.threads;
  const FoundationPoints points = DigitizeFoundation(f, l.dxf);
  // The foundation's points as `candi foundation` writes them (work/ keeps each stage's output).
  io::WriteLayerClouds((fs::path(work) / (l.name + "_foundation.ply")).string(), points.clouds, points.Names());
  LayerResult r;
  r.cloud = points.Merged();
  r.method = "reconstructed: CAD sections -> Hermite profiles -> rotational blending / sweep -> mesh -> uniform samples";
  r.parameters = {{"sections", f.layers},
                  {"samples_per_side", f.surface.profile.samples_per_side},
                  {"angular_steps", f.surface.revolve.angular_steps},
                  {"mode", mesh::RevolveModeName(f.surface.revolve.mode)},
                  {"seed", scene.seed}};
  if (f.sample.count)
    r.parameters["count"] = f.sample.count;
  else
    r.parameters["density"] = f.sample.density;
  return r;
}

// Each panel: photo -> depth (network) -> metric points in the panel frame (options.relief), or
// its point file; then each panel's world_from_panel from the correspondences CSV (Ceres,
// reconstruction/relief/relief_place.h). A panel that does not fit is a warning; a panel without
// correspondences is an error.
LayerResult Relief(const BuildOptions& options, const SceneLayer& l, const std::string& work) {
  const std::vector<relief::PanelCorrespondence> correspondences = relief::ReadPanelCorrespondences(l.placement);
  const relief::PlacementResult placed =
      relief::PlacePanels(relief::PanelPlacementOptions(), correspondences, l.placement);
  std::map<std::string, const relief::PanelPlacement*> by_id;
  for (const relief::PanelPlacement& p : placed.panels) by_id[p.panel] = &p;
  for (const ReliefPanelSpec& p : l.panels) {
    if (!by_id.count(p.id)) {
      throw InputError(l.placement, "", "panel '" + p.id + "' of layer '" + l.name + "' has no correspondences");
    }
  }
  const ReliefPanelRunner run = options.relief ? options.relief : ReliefInChildProcesses();
  LayerResult r;
  r.cloud.schema.colors = true;
  r.cloud.SetSchema(r.cloud.schema);
  r.cloud.frame = placed.frame;
  json panels = json::array();
  ConsoleProgressOptions po;
  po.unit = "panels";
  ConsoleProgress progress("relief panels of " + l.name, po);
  for (size_t k = 0; k < l.panels.size(); ++k) {
    const ReliefPanelSpec& p = l.panels[k];
    std::string points = p.points;
    if (points.empty()) {
      ReliefPanelJob job;
      job.log_base = (fs::path(work) / (l.name + "_" + p.id)).string();
      job.photo = p.photo;
      job.model = l.model;
      job.predict_width_m = p.native_resolution ? 0.0 : l.width_m;  // 0: no resampling
      job.width_m = l.width_m;
      job.depth = job.log_base + "_depth.png";
      job.points = job.log_base + "_panel.ply";
      run(job);
      points = job.points;
    }
    const relief::PanelPlacement& placement = *by_id.at(p.id);
    if (!placement.fits) {
      LogWarning("layer " + l.name + ": panel " + p.id + " does not fit its documented position (" + placement.status +
                 ", RMS " + FormatDouble(placement.rms_mm) + " mm); placed anyway");
    }
    const PointCloud panel = io::ReadPointCloud(points);
    for (size_t i = 0; i < panel.size(); ++i) {
      r.cloud.positions.push_back(
          r.cloud.frame.ToLocal(placement.world_from_panel * panel.frame.ToWorld(panel.positions[i])));
      r.cloud.colors.push_back(panel.schema.colors ? panel.colors[i] : Rgb8{200, 200, 200});
    }
    panels.push_back({{"id", p.id}, {"status", placement.status}, {"rms_mm", placement.rms_mm},
                      {"max_mm", placement.max_mm}, {"points", panel.size()},
                      {"prediction", p.points.empty() ? (p.native_resolution ? "photo resolution" : "model resolution")
                                                      : "given points"}});
    progress.Update(k + 1, l.panels.size());
  }
  progress.Finish();
  r.method = l.panels.front().photo.empty()
                 ? "panel points placed by Ceres from documented wall positions"
                 : "reconstructed: one old photo per panel -> depth network -> metric points -> Ceres placement";
  r.parameters = {{"panels", panels}, {"width_m", l.width_m}, {"misfits", placed.misfits}};
  if (!l.model.empty()) r.parameters["model"] = l.model;
  return r;
}

// COLMAP's executable: $CANDI_COLMAP when set, as `candi sfm` takes it.
std::string ColmapExecutable(const std::string& fallback) {
  const char* env = std::getenv("CANDI_COLMAP");
  return env != nullptr && *env != '\0' ? env : fallback;
}

LayerResult Photogrammetry(const BuildOptions& options, const Scene& scene, const SceneLayer& l,
                           const std::string& work) {
  std::string workspace = l.workspace;
  LayerResult r;
  r.method = "scanned: photogrammetry (dense multi-view stereo)";
  bool chunked = false;  // mapped in chunks: the model is in the targets' frame already
  LocalFrame chunked_frame;
  if (!l.images.empty()) {
    photogrammetry::SfmOptions sfm = l.sfm;
    sfm.colmap = ColmapExecutable(sfm.colmap);
    sfm.overwrite = true;
    const std::string sfm_dir = (fs::path(work) / (l.name + "_sfm")).string();
    const photogrammetry::SfmSummary report = StructureFromMotion(sfm, l.images, sfm_dir);
    workspace = (fs::path(sfm_dir) / "dense").string();
    r.method = "scanned: photogrammetry (COLMAP structure from motion, dense multi-view stereo)";
    r.parameters["sfm"] = {{"max_image_size", sfm.max_image_size}, {"max_features", sfm.max_features},
                           {"camera_model", sfm.camera_model}, {"workspace", sfm_dir},
                           {"colmap_version", report.colmap.version},
                           {"matcher", "candi exact brute force, " + report.matcher},
                           {"reproducibility", kSfmReproducibility}};
    if (!sfm.chunks.targets.empty()) {
      json chunks = json::array();
      for (const photogrammetry::ChunkResult& k : report.chunked.chunks) {
        chunks.push_back({{"name", k.name}, {"registered", k.registered}, {"photos", k.images}, {"tied", k.tied},
                          {"reason", k.reason}, {"control_rmse_m", k.control.d3}, {"check_rmse_m", k.check.d3}});
      }
      r.parameters["sfm"]["chunks"] = chunks;
      const photogrammetry::JointAdjustmentResult& j = report.chunked.joint;
      r.parameters["sfm"]["joint_adjustment"] = {{"ran", j.ran}, {"reason", j.reason}, {"links", j.links},
                                                 {"observations_added", j.extended},
                                                 {"control_rmse_m", j.control.d3}, {"check_rmse_m", j.check.d3}};
      chunked_frame = report.chunked.frame;
      chunked = true;
    }
  }
  if (!workspace.empty()) {
    DenseOptions d;
    d.stereo = l.stereo;
    d.stereo.seed = scene.seed;
    d.stereo.threads = options.threads;
    d.write_maps = false;
    DenseCloud dense = DenseStereo(d, workspace);
    io::WritePointCloud((fs::path(work) / (l.name + "_dense.ply")).string(), dense.cloud);
    r.cloud = std::move(dense.cloud);
    r.parameters["dense"] = {{"iterations", d.stereo.iterations}, {"window", d.stereo.window_radius},
                             {"views", d.stereo.num_source_views}, {"resolution_scale", d.stereo.resolution_scale}};
  } else {
    r.cloud = io::ReadPointCloud(l.dense);
  }
  if (chunked) {
    // The merged model is the survey frame less its shift: the points need no second fit.
    r.cloud.frame = chunked_frame;
    r.parameters["georeferenced_by"] = l.targets;
    r.parameters["picks"] = l.picks;
  } else if (!l.targets.empty()) {
    GeorefOptions g;
    g.crs = scene.crs;
    g.targets_crs = l.targets_crs;
    photogrammetry::ColmapGeorefInput model;
    if (!l.picks.empty()) model = photogrammetry::ReadColmapForGeoref((fs::path(workspace) / "sparse").string());
    const photogrammetry::GeorefResult fit = FitGeoref(g, l.targets, l.picks.empty() ? nullptr : &model, l.picks);
    for (const std::string& w : fit.fit.warnings) LogWarning(w);
    Georeference(g, fit, &r.cloud);
    const std::string georef = (fs::path(work) / (l.name + "_georef.ply")).string();
    io::WritePointCloud(georef, r.cloud);
    const json report = GeorefReport(g, fit);
    WriteFileAtomic(georef + ".georef.json", report.dump(2) + "\n");
    r.parameters["georeferenced_by"] = l.targets;
    r.parameters["georef"] = {{"rmse_m", report["rmse"]}, {"scale", report["survey_from_model"]["scale"]},
                              {"converged", report["converged"]}, {"warnings", report["warnings"]}};
    if (!l.picks.empty()) r.parameters["picks"] = l.picks;
  }
  return r;
}

}  // namespace

ReliefPanelRunner ReliefInChildProcesses() {
  return [](const ReliefPanelJob& job) {
    const std::string relief_exe = Sibling("candi-relief");
    RunChild({relief_exe, "-q", "relief", "predict", job.photo, "--model", job.model, "-o", job.depth, "--width-m",
              FormatDouble(job.predict_width_m)},
             job.log_base + "_predict.log", "relief predict of " + job.photo);
    RunChild({relief_exe, "-q", "relief", "points", job.photo, job.depth, "-o", job.points, "--width-m",
              FormatDouble(job.width_m)},
             job.log_base + "_points.log", "relief points of " + job.photo);
  };
}

namespace internal {

LayerResult Digitize(const BuildOptions& options, const Scene& scene, const SceneLayer& l, const std::string& work) {
  switch (l.kind) {
    case LayerKind::kPoints: {
      LayerResult r;
      io::PointReadOptions read;
      read.columns = l.columns;
      r.cloud = io::ReadPointCloud(l.file, read);
      r.method = "scanned: points from " + fs::path(l.file).filename().string();
      return r;
    }
    case LayerKind::kFoundation: return Foundation(options, scene, l, work);
    case LayerKind::kRelief: return Relief(options, l, work);
    case LayerKind::kPhotogrammetry: return Photogrammetry(options, scene, l, work);
  }
  throw InternalError("unknown layer kind");
}

}  // namespace internal

}  // namespace candi::pipeline

// candi build SCENE -o ARCHIVE/: the integrated archive (apps/scene.h). Each layer is digitized
// by its own path (a point file read; a foundation from its DXF; relief panels from photos through
// the depth network, placed by Ceres; photogrammetry from a dense workspace, georeferenced), moved
// by world_from_layer into the scene's one LocalFrame and written as:
//   layers/<name>.ply      double world coordinates (no shift, so every tool reads them as they are),
//                          colours, scalar_scene_layer (the layer index; CloudCompare keeps it) and a
//                          quality copy (MeshLab keeps that one)
//   archive/               the render archive of every layer (candi pack)
//   renders/<view>.png     one SPBR render per view, and its .view.json (repeatable)
//   meshlab/               float local-coordinate PLYs, scene.mlp and shift.txt
//   archive.json           provenance: sources and hashes, method, parameters, seed, version, counts,
//                          what makes the build reproducible; no run times, so that two builds of the
//                          same input give the same bytes
//   timings.json           seconds per layer, the pack, each view and in all
// Intermediate files go to work/. Every file is written atomically.
//
// Resuming (--resume): every finished stage that is worth keeping (a digitized foundation, relief
// or photogrammetry layer; the render archive; each render) leaves a checkpoint in
// work/checkpoints/<stage>.json holding a key: the SHA-256 of what the stage depends on (candi's
// version, the scene's JSON for it, the seed, the bytes of every input file (a dense workspace:
// its files' names, sizes and times), the keys of the stages it uses). A resumed build redoes only stages whose key differs or whose outputs are
// missing; archive.json marks what was reused ("resumed": true). An interrupted build (SIGINT,
// core/interrupt.h) leaves finished stages complete and nothing half-written.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <unordered_map>
#include <unordered_set>
#include <stdexcept>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "apps/output_folder.h"
#include "apps/scene.h"
#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/sha256.h"
#include "core/text_format.h"
#include "io/crs.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/colmap_runner.h"
#include "reconstruction/relief/relief_place.h"
#include "render/archive.h"

namespace candi::app {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

// This executable's sibling `name` (candi-relief for the relief stages).
std::string Sibling(const std::string& name) {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? name : (self.parent_path() / name).string();
}

void RunChild(const std::vector<std::string>& argv, const std::string& log, const std::string& what) {
  const int code = photogrammetry::RunLogged(argv, log);
  if (code != 0)
    throw InputError(log, "", what + " failed (exit code " + std::to_string(code) + "): " +
                                  photogrammetry::TailOfFile(log, 10));
}

struct LayerResult {
  PointCloud cloud;   // world coordinates (frame: the source's shift)
  std::string method;
  json parameters;
  double seconds = 0;
};

PointCloud ReadAny(const std::string& path, const std::string& columns = "") {
  io::PointReadOptions o;
  o.columns = columns;
  return io::ReadPointCloud(path, o);
}

LayerResult Foundation(const Scene& scene, const SceneLayer& l, const std::string& work) {
  FoundationArgs f;
  f.input = l.dxf;
  f.output = (fs::path(work) / (l.name + "_foundation.ply")).string();
  f.layers = l.sections;
  if (l.samples_per_side) f.samples_per_side = l.samples_per_side;
  if (l.angular_steps) f.angular_steps = l.angular_steps;
  f.density = l.density;
  f.count = l.count;
  f.mode = l.mode;
  f.seed = scene.seed;
  const int code = RunFoundation(f);
  if (code != kOk) throw InputError(l.dxf, "", "the foundation path failed (exit code " + std::to_string(code) + ")");
  LayerResult r;
  r.cloud = ReadAny(f.output);
  r.method = "reconstructed: CAD sections -> Hermite profiles -> rotational blending / sweep -> mesh -> uniform samples";
  r.parameters = {{"sections", l.sections}, {"samples_per_side", f.samples_per_side},
                  {"angular_steps", f.angular_steps}, {"mode", l.mode}, {"seed", scene.seed}};
  if (l.count) r.parameters["count"] = l.count;
  else r.parameters["density"] = l.density > 0 ? l.density : 50.0;
  return r;
}

// Each panel: photo -> depth (network) -> metric points in the panel frame (in this process when
// it holds the relief path, else by candi-relief child processes, so candi never loads libtorch),
// or its point file; then each panel's world_from_panel from the correspondences CSV (Ceres,
// reconstruction/relief/relief_place.h). A panel that does not fit is a warning; a panel without
// correspondences is an error.
LayerResult Relief(const SceneLayer& l, const std::string& work) {
  const std::vector<relief::PanelCorrespondence> correspondences = relief::ReadPanelCorrespondences(l.placement);
  const relief::PlacementResult placed = relief::PlacePanels(relief::PanelPlacementOptions(), correspondences, l.placement);
  std::map<std::string, const relief::PanelPlacement*> by_id;
  for (const relief::PanelPlacement& p : placed.panels) by_id[p.panel] = &p;
  for (const ReliefPanelSpec& p : l.panels)
    if (!by_id.count(p.id)) throw InputError(l.placement, "", "panel '" + p.id + "' of layer '" + l.name + "' has no correspondences");

  const std::string relief_exe = Sibling("candi-relief");
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
      const std::string base = (fs::path(work) / (l.name + "_" + p.id)).string();
      ReliefPredictArgs predict;
      predict.photo = p.photo, predict.model = l.model, predict.output = base + "_depth.png";
      predict.width_m = p.native_resolution ? 0.0 : l.width_m;  // 0: no resampling
      ReliefPointsArgs to_points;
      to_points.photo = p.photo, to_points.depth = predict.output, to_points.output = base + "_panel.ply";
      to_points.width_m = l.width_m;
      if (ReliefInProcess()) {
        predict.threads = 2;
        RunReliefPredict(predict);
        RunReliefPoints(to_points);
      } else {
        const std::string w = FormatDouble(l.width_m);
        RunChild({relief_exe, "-q", "relief", "predict", p.photo, "--model", l.model, "-o", predict.output,
                  "--width-m", FormatDouble(predict.width_m)}, base + "_predict.log", "relief predict of " + p.photo);
        RunChild({relief_exe, "-q", "relief", "points", p.photo, predict.output, "-o", to_points.output,
                  "--width-m", w}, base + "_points.log", "relief points of " + p.photo);
      }
      points = to_points.output;
    }
    const relief::PanelPlacement& placement = *by_id.at(p.id);
    if (!placement.fits)
      LogWarning("layer " + l.name + ": panel " + p.id + " does not fit its documented position (" +
                 placement.status + ", RMS " + FormatDouble(placement.rms_mm) + " mm); placed anyway");
    const PointCloud panel = ReadAny(points);
    for (size_t i = 0; i < panel.size(); ++i) {
      r.cloud.positions.push_back(r.cloud.frame.ToLocal(placement.world_from_panel * panel.frame.ToWorld(panel.positions[i])));
      r.cloud.colors.push_back(panel.schema.colors ? panel.colors[i] : Rgb8{200, 200, 200});
    }
    panels.push_back({{"id", p.id}, {"status", placement.status}, {"rms_mm", placement.rms_mm},
                      {"max_mm", placement.max_mm}, {"points", panel.size()},
                      {"prediction", p.points.empty() ? (p.native_resolution ? "photo resolution" : "model resolution") : "given points"}});
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

LayerResult Photogrammetry(const Scene& scene, const SceneLayer& l, const std::string& work) {
  std::string dense = l.dense, workspace = l.workspace;
  LayerResult r;
  r.method = "scanned: photogrammetry (dense multi-view stereo)";
  if (!l.images.empty()) {
    SfmArgs sfm;
    sfm.images = l.images;
    sfm.workspace = (fs::path(work) / (l.name + "_sfm")).string();
    sfm.max_image_size = l.max_image_size;
    sfm.max_features = l.max_features;
    sfm.overwrite = true;
    if (RunSfm(sfm) != kOk) throw InputError(l.images, "", "structure from motion failed");
    workspace = (fs::path(sfm.workspace) / "dense").string();
    r.method = "scanned: photogrammetry (COLMAP structure from motion, dense multi-view stereo)";
    const json report = json::parse(ReadFileToString((fs::path(sfm.workspace) / "sfm_report.json").string()));
    r.parameters["sfm"] = {{"max_image_size", sfm.max_image_size}, {"max_features", sfm.max_features},
                           {"camera_model", sfm.camera_model}, {"workspace", sfm.workspace},
                           {"colmap_version", report.value("colmap_version", "")},
                           {"matcher", report.value("matcher", "")},
                           {"reproducibility", report.value("reproducibility", "")}};
  }
  if (!workspace.empty()) {
    DenseArgs d;
    d.workspace = workspace;
    d.output = (fs::path(work) / (l.name + "_dense.ply")).string();
    d.no_maps = true;
    d.seed = scene.seed;
    d.resolution_scale = l.resolution_scale;
    d.iterations = l.iterations;
    if (RunDense(d) != kOk) throw InputError(workspace, "", "dense stereo failed");
    dense = d.output;
    r.parameters["dense"] = {{"iterations", d.iterations}, {"window", d.window}, {"views", d.views},
                             {"resolution_scale", d.resolution_scale}};
  }
  if (!l.targets.empty()) {
    GeorefArgs g;
    g.input = dense;
    g.targets = l.targets;
    g.crs = scene.crs;
    g.targets_crs = l.targets_crs;
    if (!l.picks.empty()) g.picks = l.picks, g.model = (fs::path(workspace) / "sparse").string();
    g.output = (fs::path(work) / (l.name + "_georef.ply")).string();
    if (RunGeoref(g) != kOk) throw InputError(l.targets, "", "georeferencing failed");
    dense = g.output;
    r.parameters["georeferenced_by"] = l.targets;
    const json report = json::parse(ReadFileToString(g.output + ".georef.json"));
    r.parameters["georef"] = {{"rmse_m", report["rmse"]}, {"scale", report["survey_from_model"]["scale"]},
                              {"converged", report["converged"]}, {"warnings", report["warnings"]}};
    if (!l.picks.empty()) r.parameters["picks"] = l.picks;
  }
  r.cloud = ReadAny(dense);
  return r;
}

// Drops the points of `target` that `by` covers: their voxel (edge `voxel`, on the scene frame's
// local grid) holds >= 3 points of `by`, and a point of `by` lies in their fine cell (edge
// voxel / 8) or one of the 26 around it. The second test keeps a few stray points of `by` from
// cutting a hole in a surface of `target` they do not cover (the demo's close range had stray
// points on the encasement, and hidden panels showed through the holes). Close-range data
// supersedes a coarse scan where it has data. Both clouds are in the scene's frame. Returns the
// number of points dropped.
size_t ReplaceWhereCovered(const PointCloud& by, double voxel, PointCloud* target) {
  using Cell = Eigen::Array<int64_t, 3, 1>;
  auto cell = [](const Eigen::Vector3d& p, double size) -> Cell {
    // Clamped to +-2^20 cells (a 0.5 m voxel's fine cells cover +-65 km).
    return (p / size).array().floor().max(-1048576.0).min(1048575.0).cast<int64_t>();
  };
  auto key = [](const Cell& c) {  // 21 bits per axis
    auto axis = [](int64_t v) { return static_cast<uint64_t>(v + 1048576) & 0x1fffff; };
    return axis(c.x()) << 42 | axis(c.y()) << 21 | axis(c.z());
  };
  const double fine = voxel / 8;
  std::unordered_map<uint64_t, uint32_t> counts;
  std::unordered_set<uint64_t> occupied;
  for (const Eigen::Vector3d& p : by.positions) {
    if (!p.allFinite()) continue;
    ++counts[key(cell(p, voxel))];
    occupied.insert(key(cell(p, fine)));
  }
  auto near_by = [&](const Eigen::Vector3d& p) {
    const Cell c = cell(p, fine);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz)
          if (occupied.count(key(c + Cell(dx, dy, dz)))) return true;
    return false;
  };
  std::vector<uint8_t> keep(target->size(), 1);
  for (size_t i = 0; i < target->size(); ++i) {
    const auto it = counts.find(key(cell(target->positions[i], voxel)));
    keep[i] = it == counts.end() || it->second < 3 || !near_by(target->positions[i]);
  }
  return target->Keep(keep);
}

// The layer's coordinates into the scene's CRS (scene.h, "crs"): a layer stating another CRS is
// transformed with PROJ; one stating none is taken to be in the scene's, with a warning. Points
// outside the target CRS's domain become NaN (dropped and counted by Place). Returns what
// archive.json records of the layer's CRS.
json ToSceneCrs(const Scene& scene, size_t k, PointCloud* cloud) {
  const SceneLayer& l = scene.layers[k];
  const std::string at = "/layers/" + std::to_string(k) + "/crs";
  std::string stated = cloud->meta.crs;
  if (l.crs == "scene") {
    if (!stated.empty() && !io::SameCrs(stated, scene.crs))
      throw InputError(scene.path, at, "layer " + l.name + " says \"scene\" (" + io::CrsLabel(scene.crs) +
                                           ") but its data states " + io::CrsLabel(stated));
    stated = scene.crs;
  } else if (!l.crs.empty()) {
    if (!stated.empty() && !io::SameCrs(stated, l.crs))
      throw InputError(scene.path, at, "layer " + l.name + " declares " + io::CrsLabel(l.crs) +
                                           " but its data states " + io::CrsLabel(stated) + "; remove one");
    stated = l.crs;
  }
  json record = {{"stated", stated.empty() ? json() : json(io::CrsLabel(stated))}, {"transformed", false}};
  if (stated.empty()) {
    if (!scene.crs.empty())
      LogWarning("layer " + l.name + " states no CRS; taken to be in the scene's, " + io::CrsLabel(scene.crs) +
                 " (say so with \"crs\": \"scene\" in the layer)");
    cloud->meta.crs = scene.crs;
    return record;
  }
  cloud->meta.crs = stated;
  if (scene.crs.empty() || io::SameCrs(stated, scene.crs)) return record;
  const io::CrsTransform transform(stated, scene.crs, scene.path);
  for (Eigen::Vector3d& p : cloud->positions) p = cloud->frame.ToWorld(p);
  cloud->frame = LocalFrame();
  const size_t outside = transform.Apply(&cloud->positions);
  cloud->meta.crs = scene.crs;
  LogInfo("layer " + l.name + ": " + io::CrsLabel(stated) + " -> " + io::CrsLabel(scene.crs) + " with PROJ (" +
          transform.operation() + ")");
  if (outside > 0) LogWarning("layer " + l.name + ": " + std::to_string(outside) + " points lie outside " + io::CrsLabel(scene.crs));
  record["transformed"] = true;
  record["to"] = io::CrsLabel(scene.crs);
  record["operation"] = transform.operation();
  record["accuracy_m"] = transform.accuracy();
  record["outside_domain"] = outside;
  return record;
}

// Without a scene CRS, every layer that states one must state the same: the scene's CRS then.
std::string CommonCrs(const Scene& scene, const std::vector<PointCloud*>& clouds) {
  if (!scene.crs.empty()) return scene.crs;
  std::string common;
  size_t first = 0;
  for (size_t k = 0; k < clouds.size(); ++k) {
    const std::string& c = clouds[k]->meta.crs;
    if (c.empty()) continue;
    if (common.empty()) {
      common = c, first = k;
    } else if (!io::SameCrs(common, c)) {
      throw InputError(scene.path, "/crs", "layers " + scene.layers[first].name + " (" + io::CrsLabel(common) + ") and " +
                                               scene.layers[k].name + " (" + io::CrsLabel(c) +
                                               ") are in different CRSs; declare the scene's \"crs\" to transform "
                                               "them into one with PROJ");
    }
  }
  return common;
}

LayerResult Digitize(const Scene& scene, const SceneLayer& l, const std::string& work) {
  switch (l.kind) {
    case LayerKind::kPoints: {
      LayerResult r;
      r.cloud = ReadAny(l.file, l.columns);
      r.method = "scanned: points from " + fs::path(l.file).filename().string();
      return r;
    }
    case LayerKind::kFoundation: return Foundation(scene, l, work);
    case LayerKind::kRelief: return Relief(l, work);
    case LayerKind::kPhotogrammetry: return Photogrammetry(scene, l, work);
  }
  throw InternalError("unknown layer kind");
}

// Checkpoints of finished stages (see the top of the file).
class Checkpoints {
 public:
  Checkpoints(const fs::path& dir, bool resume) : dir_(dir), resume_(resume) { fs::create_directories(dir); }

  // The stage's checkpoint when resuming and its key matches (and every file in `outputs`
  // exists). Otherwise nothing, and the checkpoint is removed: the stage is about to be redone,
  // and its outputs may be replaced before its new checkpoint is written.
  std::optional<json> Find(const std::string& stage, const std::string& key,
                           const std::vector<fs::path>& outputs) const {
    const fs::path file = dir_ / (stage + ".json");
    std::error_code ec;
    if (resume_ && fs::exists(file, ec)) {
      const json j = json::parse(ReadFileToString(file.string()), nullptr, /*allow_exceptions=*/false);
      bool complete = j.is_object() && j.value("key", "") == key;
      for (const fs::path& o : outputs) complete = complete && fs::exists(o, ec);
      if (complete) return j;
    }
    fs::remove(file, ec);
    return std::nullopt;
  }

  // Records a finished stage (after its outputs are committed).
  void Save(const std::string& stage, const std::string& key, json data) const {
    data["key"] = key;
    WriteFileAtomic((dir_ / (stage + ".json")).string(), data.dump(1) + "\n");
    // For tests (tests/fault_test.cc): CANDI_TEST_INTERRUPT_AFTER=<stage> interrupts the build
    // right after this checkpoint, as a user's Ctrl-C would, at a point that no timing decides.
    // The interrupt handler's thread ends the process; this one waits for it.
    const char* interrupt_after = std::getenv("CANDI_TEST_INTERRUPT_AFTER");
    if (interrupt_after != nullptr && stage == interrupt_after) {
      kill(getpid(), SIGINT);
      for (;;) pause();
    }
  }

 private:
  fs::path dir_;
  bool resume_;
};

// SHA-256 of files, each read once per build.
class FileHashes {
 public:
  const std::string& operator()(const std::string& path) {
    auto it = hashes_.find(path);
    if (it == hashes_.end()) it = hashes_.emplace(path, Sha256OfFile(path)).first;
    return it->second;
  }

 private:
  std::map<std::string, std::string> hashes_;
};

// A folder's fingerprint for a key: every file's relative path, size and modification time (a
// dense workspace holds gigabytes of images and maps; reading them all would cost minutes).
std::string FolderFingerprint(const std::string& dir) {
  std::vector<std::string> entries;
  std::error_code ec;
  for (fs::recursive_directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file(ec)) continue;
    const auto mtime = fs::last_write_time(it->path(), ec).time_since_epoch().count();
    entries.push_back(fs::relative(it->path(), dir, ec).string() + " " + std::to_string(it->file_size(ec)) + " " +
                      std::to_string(mtime));
  }
  std::sort(entries.begin(), entries.end());
  std::string text;
  for (const std::string& e : entries) text += e + "\n";
  return Sha256Hex(text);
}

std::string Key(const std::vector<std::string>& parts) {
  std::string text = CANDI_VERSION;
  for (const std::string& p : parts) text += "\n" + p;
  return Sha256Hex(text);
}

// A digitized layer kept for a resumed build: its points (double precision, the source's frame)
// and what archive.json says of it.
void SaveLayer(const Checkpoints& checkpoints, const std::string& stage, const std::string& key,
               const fs::path& points, const LayerResult& r) {
  io::PointWriteOptions o;
  o.precision = io::PositionPrecision::kFloat64;
  io::WritePointCloud(points.string(), r.cloud, o);
  checkpoints.Save(stage, key, {{"method", r.method}, {"parameters", r.parameters}, {"seconds", r.seconds}});
}

LayerResult LoadLayer(const json& checkpoint, const fs::path& points) {
  LayerResult r;
  r.cloud = ReadAny(points.string());
  r.method = checkpoint.at("method").get<std::string>();
  r.parameters = checkpoint.at("parameters");
  r.seconds = checkpoint.at("seconds").get<double>();
  return r;
}

// world_from_layer, the colour override, the scene's frame; NaN positions are dropped (counted).
size_t Place(const SceneLayer& l, uint16_t id, const LocalFrame& scene_frame, PointCloud* cloud) {
  PointCloud& c = *cloud;
  std::vector<uint8_t> finite(c.size(), 1);
  for (size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3d world = l.world_from_layer * c.frame.ToWorld(c.positions[i]);
    finite[i] = world.allFinite();
    if (!finite[i]) continue;
    c.positions[i] = scene_frame.ToLocal(world);
    if (c.schema.normals) {
      const Eigen::Vector3d n = l.world_from_layer.rotation * c.normals[i].cast<double>();
      c.normals[i] = n.cast<float>();
    }
  }
  const size_t dropped = c.Keep(finite);
  c.frame = scene_frame;
  PointSchema schema = c.schema;
  schema.colors = true;
  schema.scalars.clear();
  schema.scalars.push_back({"scene_layer", ScalarType::kFloat32});
  schema.scalars.push_back({"quality", ScalarType::kFloat32});
  const bool had_colors = c.schema.colors;
  c.SetSchema(schema);
  for (size_t i = 0; i < c.size(); ++i) {
    if (l.color || !had_colors) c.colors[i] = l.color ? *l.color : Rgb8{180, 180, 180};
    c.scalars[0].Set(i, id);
    c.scalars[1].Set(i, id);
  }
  return dropped;
}

// A layer in double world coordinates and no shift, so that tools which ignore candi's shift
// comment and sidecar (CloudCompare, PDAL, ...) read the real positions; the scene's frame is in
// archive.json and meshlab/shift.txt. (Double keeps 10^-9 m at 10^7 m.)
void WriteWorldPly(const std::string& path, const PointCloud& cloud) {
  io::PointWriteOptions o;
  o.precision = io::PositionPrecision::kFloat64;
  const std::unique_ptr<io::PointWriter> writer =
      io::OpenPointWriter(path, io::PointWriteSpec{cloud.schema, LocalFrame(), cloud.meta, cloud.size()}, o);
  writer->Write(cloud);  // re-expressed from the scene's frame (exact for its integer origin)
  writer->Close();
}

// A MeshLab project: float PLYs in local coordinates (MeshLab reads matrices as float, so world
// coordinates of 10^6 m would lose centimetres) and the shift beside it.
void WriteMeshlab(const Scene& scene, const std::vector<PointCloud>& clouds, const std::string& dir) {
  fs::create_directories(dir);
  std::string mlp = "<!DOCTYPE MeshLabDocument>\n<MeshLabProject>\n <MeshGroup>\n";
  for (size_t k = 0; k < clouds.size(); ++k) {
    PointCloud local = clouds[k];
    local.frame = LocalFrame();
    io::PointWriteOptions o;
    o.precision = io::PositionPrecision::kFloat32;
    io::WritePointCloud((fs::path(dir) / (scene.layers[k].name + ".ply")).string(), local, o);
    mlp += "  <MLMesh label=\"" + scene.layers[k].name + "\" filename=\"" + scene.layers[k].name +
           ".ply\" visible=\"1\">\n   <MLMatrix44>\n1 0 0 0 \n0 1 0 0 \n0 0 1 0 \n0 0 0 1 \n</MLMatrix44>\n"
           "   <RenderingOption pointSize=\"1\" wireColor=\"64 64 64 255\" boxColor=\"234 234 234 255\" "
           "solidColor=\"192 192 192 255\" pointColor=\"131 149 69 255\">100001000000000000000100000001010100000010100000000100111011110000001001</RenderingOption>\n"
           "  </MLMesh>\n";
  }
  mlp += " </MeshGroup>\n <RasterGroup/>\n</MeshLabProject>\n";
  WriteFileAtomic((fs::path(dir) / "scene.mlp").string(), mlp);
  const Eigen::Vector3d o = clouds.empty() ? Eigen::Vector3d::Zero() : clouds.front().frame.origin;
  char shift[256];
  std::snprintf(shift, sizeof(shift),
                "# world = local + shift (metres); the PLYs here are in local coordinates\n%.17g %.17g %.17g\n",
                o.x(), o.y(), o.z());
  WriteFileAtomic((fs::path(dir) / "shift.txt").string(), shift);
}

}  // namespace

int RunBuild(const BuildArgs& args) {
  const auto start = std::chrono::steady_clock::now();
  const Scene scene = LoadScene(args.scene);
  CheckOutputFolder(args.output);
  std::error_code ec;
  fs::create_directories(args.output, ec);
  if (ec) throw InputError(args.output, "", "cannot create the output folder: " + ec.message());
  const fs::path out(args.output);
  const std::string work = (out / "work").string();
  for (const char* sub : {"work", "layers", "renders"}) fs::create_directories(out / sub);

  const Checkpoints checkpoints(out / "work" / "checkpoints", args.resume);
  FileHashes hashes;
  const json scene_json = json::parse(scene.text);  // valid: LoadScene parsed it
  const std::string seed = std::to_string(scene.seed);

  // 1. Digitize every layer, in world coordinates. A layer's key: its JSON, the seed, its inputs.
  std::vector<LayerResult> results;
  std::vector<std::string> layer_keys;
  std::vector<bool> layer_resumed;
  std::vector<json> crs_records;
  Box3d world_box;
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    const SceneLayer& l = scene.layers[k];
    std::vector<std::string> parts = {"layer", scene_json["layers"][k].dump(), seed};
    for (const std::string& s : l.Sources()) parts.push_back(hashes(s));
    if (!l.workspace.empty()) parts.push_back(FolderFingerprint(l.workspace));
    layer_keys.push_back(Key(parts));
    // Point files are read, not digitized: nothing to keep.
    const bool keep = l.kind != LayerKind::kPoints;
    const std::string stage = "layer_" + l.name;
    const fs::path kept = out / "work" / (l.name + "_digitized.ply");
    LayerResult r;
    const std::optional<json> checkpoint = keep ? checkpoints.Find(stage, layer_keys.back(), {kept}) : std::nullopt;
    layer_resumed.push_back(checkpoint.has_value());
    if (checkpoint) {
      LogInfo("layer " + l.name + " (" + LayerKindName(l.kind) + "): resumed from " + kept.string());
      r = LoadLayer(*checkpoint, kept);
    } else {
      LogInfo("layer " + l.name + " (" + LayerKindName(l.kind) + ")");
      const auto t = std::chrono::steady_clock::now();
      r = Digitize(scene, l, work);
      r.seconds = Seconds(t);
      if (keep) SaveLayer(checkpoints, stage, layer_keys.back(), kept, r);
    }
    crs_records.push_back(ToSceneCrs(scene, k, &r.cloud));
    for (size_t i = 0; i < r.cloud.size(); ++i) {
      const Eigen::Vector3d w = l.world_from_layer * r.cloud.frame.ToWorld(r.cloud.positions[i]);
      if (w.allFinite()) world_box.Extend(w);
    }
    results.push_back(std::move(r));
  }
  const LocalFrame frame = scene.origin ? LocalFrame{*scene.origin} : LocalFrame::Auto(world_box);
  std::vector<PointCloud*> digitized;
  for (LayerResult& r : results) digitized.push_back(&r.cloud);
  const std::string scene_crs = CommonCrs(scene, digitized);

  // 2. Place, colour and write each layer.
  std::vector<std::string> layer_files;
  std::vector<PointCloud> clouds;
  std::vector<size_t> dropped;
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    const SceneLayer& l = scene.layers[k];
    dropped.push_back(Place(l, static_cast<uint16_t>(k), frame, &results[k].cloud));
    if (dropped.back() > 0) LogWarning("layer " + l.name + ": " + std::to_string(dropped.back()) + " points with NaN coordinates dropped");
  }
  // Layers that supersede others where they have points (in scene order).
  std::vector<json> replaced(scene.layers.size(), json::object());
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    for (const std::string& name : scene.layers[k].replaces) {
      const size_t t = static_cast<size_t>(
          std::find_if(scene.layers.begin(), scene.layers.end(), [&](const SceneLayer& l) { return l.name == name; }) -
          scene.layers.begin());
      const size_t n = ReplaceWhereCovered(results[k].cloud, scene.layers[k].replace_voxel, &results[t].cloud);
      replaced[t][scene.layers[k].name] = n;
      LogInfo("layer " + scene.layers[k].name + " replaces " + std::to_string(n) + " points of layer " + name +
              " (" + FormatDouble(scene.layers[k].replace_voxel) + " m cubes)");
    }
  }
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    const SceneLayer& l = scene.layers[k];
    const std::string file = (out / "layers" / (l.name + ".ply")).string();
    WriteWorldPly(file, results[k].cloud);
    layer_files.push_back(file);
    clouds.push_back(std::move(results[k].cloud));
  }

  // 3. The render archive of every layer (key: the layers' keys and the scene's origin).
  // The archive format's version is part of the key: a build resumed by a newer candi repacks.
  std::vector<std::string> pack_parts = {"pack", "archive v" + std::to_string(render::kArchiveVersion),
                                         scene_json.value("origin", json()).dump()};
  pack_parts.insert(pack_parts.end(), layer_keys.begin(), layer_keys.end());
  const std::string pack_key = Key(pack_parts);
  PackArgs pack;
  pack.inputs = layer_files;
  pack.output = (out / "archive").string();
  double pack_seconds = 0;
  const std::optional<json> pack_checkpoint = checkpoints.Find("pack", pack_key, {out / "archive" / render::kArchiveManifest});
  if (pack_checkpoint) {
    LogInfo("render archive: resumed from " + pack.output);
    pack_seconds = pack_checkpoint->at("seconds").get<double>();
  } else {
    const auto t_pack = std::chrono::steady_clock::now();
    if (RunPack(pack) != kOk) throw InputError(pack.output, "", "packing failed");
    pack_seconds = Seconds(t_pack);
    checkpoints.Save("pack", pack_key, {{"seconds", pack_seconds}});
  }

  json timings = {{"layers", json::object()}, {"views", json::object()}};  // seconds, apart from archive.json
  // 4. Renders (key: the view's and the render settings' JSON, the seed, the keys of its layers).
  json views = json::array();
  for (size_t vi = 0; vi < scene.views.size(); ++vi) {
    const SceneView& v = scene.views[vi];
    const auto t = std::chrono::steady_clock::now();
    RenderArgs r;
    std::vector<std::string> parts = {"view", scene_json["views"][vi].dump(),
                                      scene_json.value("render", json()).dump(), seed, pack_key};
    if (!v.camera_file.empty()) parts.push_back(hashes(v.camera_file));
    for (size_t k = 0; k < scene.layers.size(); ++k) {
      const SceneLayer& l = scene.layers[k];
      if (!v.layers.empty() && std::find(v.layers.begin(), v.layers.end(), l.name) == v.layers.end()) continue;
      r.inputs.push_back(layer_files[k]);
      if (!v.opaque) r.alpha.push_back(ViewOpacity(v, l));
    }
    r.output = (out / "renders" / (v.name + ".png")).string();
    r.repeat_level = scene.repeat_level;
    r.seed = scene.seed;
    r.size = std::to_string(scene.width) + "x" + std::to_string(scene.height);
    r.size_given = true;
    r.background = std::to_string(scene.background.r) + "," + std::to_string(scene.background.g) + "," +
                   std::to_string(scene.background.b);
    r.brightness = scene.brightness;
    r.opaque = v.opaque;
    r.point_size = v.point_size;
    r.mode = "memory";
    r.threads = args.threads;
    const std::string view_file = (out / "renders" / (v.name + ".view.json")).string();
    if (!v.camera_file.empty()) r.view = v.camera_file;
    if (!v.camera_json.empty()) {
      WriteFileAtomic(view_file, v.camera_json + "\n");
      r.view = view_file;
    }
    if (r.view.empty()) r.save_view = view_file;
    const std::string key = Key(parts), stage = "view_" + v.name;
    std::vector<fs::path> outputs = {r.output};
    if (v.camera_file.empty()) outputs.push_back(view_file);
    const std::optional<json> checkpoint = checkpoints.Find(stage, key, outputs);
    double seconds = 0;
    if (checkpoint) {
      LogInfo("view " + v.name + ": resumed from " + r.output);
      seconds = checkpoint->at("seconds").get<double>();
    } else {
      if (RunRender(r) != kOk) throw InputError(r.output, "", "render failed");
      seconds = Seconds(t);
      checkpoints.Save(stage, key, {{"seconds", seconds}});
    }
    json alphas = json::object();
    for (size_t k = 0; k < r.alpha.size(); ++k) alphas[fs::path(r.inputs[k]).stem().string()] = r.alpha[k];
    views.push_back({{"name", v.name}, {"png", "renders/" + v.name + ".png"}, {"opaque", v.opaque},
                     {"opacity", alphas}, {"resumed", checkpoint.has_value()}});
    timings["views"][v.name] = seconds;
  }

  // 5. MeshLab project, provenance.
  WriteMeshlab(scene, clouds, (out / "meshlab").string());
  json layers = json::array();
  uint64_t total = 0;
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    const SceneLayer& l = scene.layers[k];
    json sources = json::array();
    for (const std::string& s : l.Sources()) sources.push_back({{"path", s}, {"sha256", hashes(s)}, {"bytes", fs::file_size(s)}});
    const Eigen::Matrix4d m = l.world_from_layer.ToMatrix();
    json matrix = json::array();
    for (int r = 0; r < 4; ++r) matrix.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
    total += clouds[k].size();
    layers.push_back({{"name", l.name}, {"kind", LayerKindName(l.kind)},
                      {"scanned", l.kind == LayerKind::kPoints || l.kind == LayerKind::kPhotogrammetry},
                      {"method", results[k].method}, {"parameters", results[k].parameters},
                      {"sources", sources}, {"world_from_layer", matrix}, {"opacity", l.opacity},
                      {"highlight", l.highlight}, {"points", clouds[k].size()}, {"dropped_nan", dropped[k]},
                      {"replaces", l.replaces}, {"replaced_by", replaced[k]}, {"crs", crs_records[k]},
                      {"file", "layers/" + l.name + ".ply"}, {"resumed", static_cast<bool>(layer_resumed[k])}});
    timings["layers"][l.name] = results[k].seconds;
  }
  const json provenance = {
      {"candi_version", CANDI_VERSION}, {"scene", {{"path", scene.path}, {"sha256", Sha256Hex(scene.text)}}},
      {"name", scene.name}, {"seed", scene.seed},
      {"frame", {{"origin", {frame.origin.x(), frame.origin.y(), frame.origin.z()}}}},
      {"crs", scene_crs.empty() ? json() : json({{"definition", scene_crs}, {"label", io::CrsLabel(scene_crs)}})},
      {"points", total}, {"layers", layers}, {"archive", "archive"},
      {"pack_resumed", pack_checkpoint.has_value()},
      {"views", views}, {"meshlab", "meshlab/scene.mlp"},
      {"reproducibility",
       {{"seed", scene.seed},
        {"same_bytes", "the same sources (their SHA-256 above), scene, seed, candi version and COLMAP build on the "
                       "same machine give byte-identical layers/, archive/, renders/, meshlab/ and this file, for "
                       "any thread count; run times are kept apart, in timings.json"},
        {"how", "every random step draws from the scene's seed; parallel work is split and reduced in a fixed "
                "order; photos: COLMAP's image ids follow the photo names, candi matches the features exactly "
                "(brute force), COLMAP verifies and maps on one thread with its random seed fixed"},
        {"across_machines", "not guaranteed: another CPU or C library can round floating point differently "
                            "(COLMAP's SIFT, Ceres, libm), and one differing bit can change what COLMAP's "
                            "mapper registers (README, Reproducibility)"}}}};
  WriteFileAtomic((out / "archive.json").string(), provenance.dump(2) + "\n");
  timings["pack"] = pack_seconds;
  timings["total"] = Seconds(start);
  WriteFileAtomic((out / "timings.json").string(), timings.dump(2) + "\n");

  std::printf("%-16s %-15s %12s %8s %-8s %s\n", "layer", "kind", "points", "opacity", "scanned", "seconds");
  for (size_t k = 0; k < scene.layers.size(); ++k)
    std::printf("%-16s %-15s %12zu %8.3g %-8s %.1f\n", scene.layers[k].name.c_str(),
                LayerKindName(scene.layers[k].kind).c_str(), clouds[k].size(), scene.layers[k].opacity,
                layers[k]["scanned"].get<bool>() ? "yes" : "no", results[k].seconds);
  std::printf("%s: %llu points in %zu layers, frame origin %s, %zu render(s), %.1f s\n", args.output.c_str(),
              static_cast<unsigned long long>(total), clouds.size(), frame.ToString().c_str(), views.size(),
              Seconds(start));
  return kOk;
}

}  // namespace candi::app

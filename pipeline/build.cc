#include "pipeline/build.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/sha256.h"
#include "core/text_format.h"
#include "core/timer.h"
#include "core/version.h"
#include "io/crs.h"
#include "io/point_io.h"
#include "pipeline/build_internal.h"
#include "pipeline/copc_export.h"
#include "pipeline/render.h"
#include "render/archive.h"
#include "render/archive_pack.h"
#include "render/build_record.h"
#include "render/view_json.h"

namespace candi::pipeline {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace internal;  // NOLINT: the build's own pieces

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

// The layer as WriteWorldPly's file holds it: world coordinates, no shift (what the renders draw).
PointCloud InWorld(const PointCloud& cloud) {
  PointCloud world = cloud;
  for (Eigen::Vector3d& p : world.positions) p = cloud.frame.ToWorld(p);
  world.frame = LocalFrame();
  return world;
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

// What the build has digitized and placed so far.
struct Layers {
  std::vector<LayerResult> results;
  std::vector<std::string> keys;
  std::vector<bool> resumed;
  std::vector<json> crs_records;
  std::vector<size_t> dropped;
  std::vector<json> replaced;
  std::vector<std::string> files;    // layers/<name>.ply
  std::vector<PointCloud> clouds;    // the scene's frame
};

// 1. Every layer digitized (or resumed), in world coordinates, into the scene's CRS. A layer's
// key: its JSON, the seed, its inputs.
void DigitizeLayers(const BuildOptions& options, const Scene& scene, const fs::path& out,
                    const Checkpoints& checkpoints, FileHashes& hashes, Layers* layers,
                    Box3d* world_box) {
  const std::string seed = std::to_string(scene.seed);
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    const SceneLayer& l = scene.layers[k];
    std::vector<std::string> parts = {"layer", l.key_json, seed};
    for (const std::string& s : l.Sources()) parts.push_back(hashes(s));
    if (!l.workspace.empty()) parts.push_back(FolderFingerprint(l.workspace));
    layers->keys.push_back(Key(parts));
    // Point files are read, not digitized: nothing to keep.
    const bool keep = l.kind != LayerKind::kPoints;
    const std::string stage = "layer_" + l.name;
    const fs::path kept = out / "work" / (l.name + "_digitized.ply");
    LayerResult r;
    const std::optional<json> checkpoint = keep ? checkpoints.Find(stage, layers->keys.back(), {kept}) : std::nullopt;
    layers->resumed.push_back(checkpoint.has_value());
    if (checkpoint) {
      LogInfo("layer " + l.name + " (" + LayerKindName(l.kind) + "): resumed from " + kept.string());
      r = LoadLayer(*checkpoint, kept);
    } else {
      LogInfo("layer " + l.name + " (" + LayerKindName(l.kind) + ")");
      const Stopwatch watch;
      r = Digitize(options, scene, l, (out / "work").string());
      r.seconds = watch.Seconds();
      if (keep) SaveLayer(checkpoints, stage, layers->keys.back(), kept, r);
    }
    layers->crs_records.push_back(ToSceneCrs(scene, k, &r.cloud));
    for (size_t i = 0; i < r.cloud.size(); ++i) {
      const Eigen::Vector3d w = l.world_from_layer * r.cloud.frame.ToWorld(r.cloud.positions[i]);
      if (w.allFinite()) world_box->Extend(w);
    }
    layers->results.push_back(std::move(r));
  }
}

// 2. Each layer placed, coloured and written; close-range layers replace what they cover.
void PlaceLayers(const Scene& scene, const LocalFrame& frame, const fs::path& out, Layers* layers) {
  std::vector<LayerResult>& results = layers->results;
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    const SceneLayer& l = scene.layers[k];
    layers->dropped.push_back(Place(l, static_cast<uint16_t>(k), frame, &results[k].cloud));
    if (layers->dropped.back() > 0) {
      LogWarning("layer " + l.name + ": " + std::to_string(layers->dropped.back()) +
                 " points with NaN coordinates dropped");
    }
  }
  // Layers that supersede others where they have points (in scene order).
  layers->replaced.assign(scene.layers.size(), json::object());
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    for (const std::string& name : scene.layers[k].replaces) {
      const size_t t = static_cast<size_t>(
          std::find_if(scene.layers.begin(), scene.layers.end(), [&](const SceneLayer& l) { return l.name == name; }) -
          scene.layers.begin());
      const size_t n = ReplaceWhereCovered(results[k].cloud, scene.layers[k].replace_voxel, &results[t].cloud);
      layers->replaced[t][scene.layers[k].name] = n;
      LogInfo("layer " + scene.layers[k].name + " replaces " + std::to_string(n) + " points of layer " + name + " (" +
              FormatDouble(scene.layers[k].replace_voxel) + " m cubes)");
    }
  }
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    const std::string file = (out / "layers" / (scene.layers[k].name + ".ply")).string();
    WriteWorldPly(file, results[k].cloud);
    layers->files.push_back(file);
    layers->clouds.push_back(std::move(results[k].cloud));
  }
}

// 3. The render archive of every layer from the layer files (key: the layers' keys and the scene's
// origin; the archive format's version too, so a build resumed by a newer candi repacks).
// Returns the pack's seconds and whether it was resumed.
std::pair<double, bool> PackLayers(const BuildOptions& options, const Scene& scene,
                                   const fs::path& out, const Checkpoints& checkpoints,
                                   const Layers& layers, std::string* pack_key) {
  std::vector<std::string> parts = {"pack", "archive v" + std::to_string(render::kArchiveVersion),
                                    scene.origin_json};
  parts.insert(parts.end(), layers.keys.begin(), layers.keys.end());
  *pack_key = Key(parts);
  const std::string archive = (out / "archive").string();
  const std::optional<json> checkpoint = checkpoints.Find("pack", *pack_key, {out / "archive" / render::kArchiveManifest});
  if (checkpoint) {
    LogInfo("render archive: resumed from " + archive);
    return {checkpoint->at("seconds").get<double>(), true};
  }
  const Stopwatch watch;
  render::PackOptions pack;
  pack.threads = options.threads;
  ConsoleProgress progress("pack");
  render::PackFiles(pack, layers.files, "", archive, progress.Callback());
  progress.Finish();
  const double seconds = watch.Seconds();
  checkpoints.Save("pack", *pack_key, {{"seconds", seconds}});
  return {seconds, false};
}

// 4. One render per view, from the layers in memory (key: the view's and the render settings'
// JSON, the seed, the archive's key): the scene's render settings, the view's opaque and point
// size. Returns the record's views; their seconds go to `timings`.
std::vector<render::BuildViewRecord> RenderViews(const BuildOptions& options, const Scene& scene,
                                                 const fs::path& out,
                                                 const Checkpoints& checkpoints, FileHashes& hashes,
                                                 const Layers& layers, const std::string& pack_key,
                                                 json* timings) {
  std::vector<PointCloud> world;  // as the layer files hold them
  for (const PointCloud& c : layers.clouds) world.push_back(InWorld(c));
  DensityCache densities;         // a layer's density serves every view
  std::vector<render::BuildViewRecord> views;
  for (const SceneView& v : scene.views) {
    const Stopwatch watch;
    std::vector<std::string> parts = {"view", v.key_json, scene.render_json,
                                      std::to_string(scene.seed), pack_key};
    if (!v.camera_file.empty()) parts.push_back(hashes(v.camera_file));
    RenderOptions r;
    std::vector<const PointCloud*> clouds;
    std::vector<std::string> names, keys;
    for (size_t k = 0; k < scene.layers.size(); ++k) {
      const SceneLayer& l = scene.layers[k];
      if (!v.layers.empty() && std::find(v.layers.begin(), v.layers.end(), l.name) == v.layers.end()) continue;
      clouds.push_back(&world[k]);
      names.push_back(layers.files[k]);
      keys.push_back("layer " + std::to_string(k));
      if (!v.opaque) r.alpha.push_back(ViewOpacity(v, l));
    }
    r.image = scene.render;
    r.image.spbr.opaque = v.opaque;
    r.image.spbr.point_size = v.point_size;
    r.size_given = true;
    r.mode = RenderMode::kMemory;
    r.threads = options.threads;
    RenderOutputs outputs;
    outputs.png = (out / "renders" / (v.name + ".png")).string();
    outputs.inputs = names;
    const std::string view_file = (out / "renders" / (v.name + ".view.json")).string();
    if (!v.camera_file.empty()) r.view = render::LoadView(v.camera_file);
    if (v.camera) {
      render::SaveView(view_file, *v.camera);
      r.view = v.camera;
    }
    if (!r.view) outputs.save_view = view_file;
    const std::string key = Key(parts), stage = "view_" + v.name;
    std::vector<fs::path> kept = {outputs.png};
    if (v.camera_file.empty()) kept.push_back(view_file);
    const std::optional<json> checkpoint = checkpoints.Find(stage, key, kept);
    double seconds = 0;
    if (checkpoint) {
      LogInfo("view " + v.name + ": resumed from " + outputs.png);
      seconds = checkpoint->at("seconds").get<double>();
    } else {
      WriteRender(r, RenderClouds(r, clouds, names, keys, &densities), outputs);
      seconds = watch.Seconds();
      checkpoints.Save(stage, key, {{"seconds", seconds}});
    }
    render::BuildViewRecord record;
    record.name = v.name;
    record.png = "renders/" + v.name + ".png";
    record.opaque = v.opaque;
    for (size_t k = 0; k < r.alpha.size(); ++k)
      record.opacity.push_back({fs::path(names[k]).stem().string(), r.alpha[k]});
    record.resumed = checkpoint.has_value();
    views.push_back(record);
    (*timings)["views"][v.name] = seconds;
  }
  return views;
}

// 5. The COPC files the scene asks for (copc_export.h), from the layer files (key: the layers'
// keys, the scene's "copc", name, CRS and origin). Returns the record's "copc" (none when none is
// asked for); the seconds go to `timings`.
std::optional<render::BuildCopcRecord> WriteSceneCopc(const BuildOptions& options,
                                                      const Scene& scene, const fs::path& out,
                                                      const Checkpoints& checkpoints,
                                                      const Layers& layers, const LocalFrame& frame,
                                                      const std::string& scene_crs, json* timings) {
  if (!scene.copc.layers && !scene.copc.scene) return std::nullopt;
  const Eigen::Vector3d& o = frame.origin;
  std::vector<std::string> parts = {"copc", scene.copc_json, scene.name, scene_crs,
                                    json::array({o.x(), o.y(), o.z()}).dump()};
  parts.insert(parts.end(), layers.keys.begin(), layers.keys.end());
  const std::string key = Key(parts);
  CopcSource source{scene.name, scene_crs, frame.origin, {}, layers.files};
  std::vector<fs::path> outputs;
  for (const SceneLayer& l : scene.layers) {
    source.layer_names.push_back(l.name);
    if (scene.copc.layers) outputs.push_back(out / "layers" / (l.name + ".copc.laz"));
  }
  const std::string scene_file = SceneCopcName(scene.name);
  if (scene.copc.scene) outputs.push_back(out / scene_file);
  std::optional<json> checkpoint = checkpoints.Find("copc", key, outputs);
  const bool resumed = checkpoint.has_value();
  render::BuildCopcRecord copc;
  if (resumed) {
    LogInfo("COPC: resumed");
    copc = render::CopcFilesFromJson(checkpoint->at("files").dump(),
                                     (out / "work" / "checkpoints").string());
  } else {
    const Stopwatch watch;
    ConsoleProgress progress("copc");
    StagedProgress closing("copc");  // each file's octree and chunks, once every point is read
    CopcOptions options_copc = scene.copc;
    options_copc.memory_bytes = options.copc_memory_bytes;
    const std::vector<CopcFile> files = WriteCopc(
        options_copc, source, (out / scene_file).string(),
        [&](uint64_t done, uint64_t total) {
          progress.Update(done, total);
          if (total > 0 && done >= total) progress.Finish();  // all read: the files close next
        },
        closing.Callback());
    closing.Finish();
    progress.Finish();
    for (const CopcFile& f : files) {
      const render::BuildCopcFileRecord record{
          fs::path(f.path).lexically_relative(out).generic_string(), f.points, f.bytes, f.layer};
      if (f.layer.empty())
        copc.scene = record;
      else
        copc.layers.push_back(record);
    }
    checkpoint = {{"seconds", watch.Seconds()},
                  {"files", json::parse(render::CopcFilesToJson(copc))}};
    checkpoints.Save("copc", key, *checkpoint);
  }
  (*timings)["copc"] = checkpoint->at("seconds");
  copc.scale_m = kCopcScale;
  copc.resumed = resumed;
  return copc;
}

std::vector<render::BuildLayerRecord> LayerRecords(const Scene& scene, FileHashes& hashes,
                                                   const Layers& layers, json* timings) {
  std::vector<render::BuildLayerRecord> out;
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    const SceneLayer& l = scene.layers[k];
    render::BuildLayerRecord r;
    r.name = l.name;
    r.kind = LayerKindName(l.kind);
    r.scanned = l.kind == LayerKind::kPoints || l.kind == LayerKind::kPhotogrammetry;
    r.method = layers.results[k].method;
    r.parameters_json = layers.results[k].parameters.dump();
    for (const std::string& src : l.Sources())
      r.sources.push_back({src, hashes(src), fs::file_size(src)});
    r.world_from_layer = l.world_from_layer.ToMatrix();
    r.opacity = l.opacity;
    r.highlight = l.highlight;
    r.points = layers.clouds[k].size();
    r.dropped_nan = layers.dropped[k];
    r.replaces = l.replaces;
    for (auto it = layers.replaced[k].begin(); it != layers.replaced[k].end(); ++it) {
      r.replaced_by.push_back({it.key(), it.value().get<uint64_t>()});
    }
    r.crs_json = layers.crs_records[k].dump();
    r.file = "layers/" + l.name + ".ply";
    r.resumed = layers.resumed[k];
    out.push_back(r);
    (*timings)["layers"][l.name] = layers.results[k].seconds;
  }
  return out;
}

render::BuildRecord Record(const Scene& scene, const LocalFrame& frame,
                           const std::string& scene_crs) {
  render::BuildRecord r;
  r.candi_version = kVersion;
  r.scene_path = scene.path;
  r.scene_sha256 = Sha256Hex(scene.text);
  r.name = scene.name;
  r.seed = scene.seed;
  r.origin = frame.origin;
  if (!scene_crs.empty()) r.crs_definition = scene_crs, r.crs_label = io::CrsLabel(scene_crs);
  r.render = scene.render;
  r.licence = scene.licence;
  for (const SceneAnnotation& a : scene.annotations)
    r.annotations.push_back({a.title, a.text, a.position, a.view, a.camera});
  return r;
}

}  // namespace

void BuildOptions::Check() const {
  CANDI_CHECK_OPTION(!output.empty(), output, "a folder");
  CANDI_CHECK_OPTION_IN(threads, 0, 256);
}

BuildSummary Build(const BuildOptions& options, const Scene& scene) {
  options.Check();
  const Stopwatch watch;
  CheckOutputFolder(options.output);
  std::error_code ec;
  fs::create_directories(options.output, ec);
  if (ec) throw InputError(options.output, "", "cannot create the output folder: " + ec.message());
  const fs::path out(options.output);
  for (const char* sub : {"work", "layers", "renders"}) fs::create_directories(out / sub);
  const Checkpoints checkpoints(out / "work" / "checkpoints", options.resume);
  FileHashes hashes;

  Layers layers;
  Box3d world_box;
  DigitizeLayers(options, scene, out, checkpoints, hashes, &layers, &world_box);
  const LocalFrame frame = scene.origin ? LocalFrame{*scene.origin} : LocalFrame::Auto(world_box);
  std::vector<PointCloud*> digitized;
  for (LayerResult& r : layers.results) digitized.push_back(&r.cloud);
  const std::string scene_crs = CommonCrs(scene, digitized);
  PlaceLayers(scene, frame, out, &layers);
  json timings = {{"layers", json::object()}, {"views", json::object()}};  // seconds, apart from archive.json
  render::BuildRecord record = Record(scene, frame, scene_crs);
  record.comparisons =
      RunComparisons(options, scene, out, checkpoints, hashes, layers.files, &timings);
  std::string pack_key;
  const auto [pack_seconds, pack_resumed] =
      PackLayers(options, scene, out, checkpoints, layers, &pack_key);
  record.pack_resumed = pack_resumed;
  record.views = RenderViews(options, scene, out, checkpoints, hashes, layers, pack_key, &timings);
  record.copc =
      WriteSceneCopc(options, scene, out, checkpoints, layers, frame, scene_crs, &timings);

  // 6. MeshLab project, provenance.
  WriteMeshlab(scene, layers.clouds, (out / "meshlab").string());
  record.layers = LayerRecords(scene, hashes, layers, &timings);
  BuildSummary summary;
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    const SceneLayer& l = scene.layers[k];
    summary.layers.push_back({l.name, l.kind, layers.clouds[k].size(), l.opacity,
                              record.layers[k].scanned, layers.results[k].seconds});
    summary.points += layers.clouds[k].size();
  }
  record.points = summary.points;
  render::WriteBuildRecord(out.string(), record);
  summary.frame = frame;
  summary.views = record.views.size();
  for (const render::BuildComparisonRecord& c : record.comparisons) {
    summary.comparisons.push_back(
        {c.name, c.method, c.count, c.mean, c.rms, c.tolerance, c.within_tolerance, c.resumed});
  }
  summary.seconds = watch.Seconds();
  timings["pack"] = pack_seconds;
  timings["total"] = summary.seconds;
  WriteFileAtomic((out / "timings.json").string(), timings.dump(2) + "\n");
  return summary;
}

}  // namespace candi::pipeline

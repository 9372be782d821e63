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

// The scene's "brightness" as a render gain: -1 automatic, 1 none, else the gain.
double SceneBrightness(const Scene& scene) {
  if (scene.brightness == "auto") return -1;
  if (scene.brightness == "none") return 1;
  return std::strtod(scene.brightness.c_str(), nullptr);
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
void DigitizeLayers(const BuildOptions& options, const Scene& scene, const json& scene_json, const fs::path& out,
                    const Checkpoints& checkpoints, FileHashes& hashes, Layers* layers, Box3d* world_box) {
  const std::string seed = std::to_string(scene.seed);
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    const SceneLayer& l = scene.layers[k];
    std::vector<std::string> parts = {"layer", scene_json["layers"][k].dump(), seed};
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
std::pair<double, bool> PackLayers(const BuildOptions& options, const json& scene_json, const fs::path& out,
                                   const Checkpoints& checkpoints, const Layers& layers, std::string* pack_key) {
  std::vector<std::string> parts = {"pack", "archive v" + std::to_string(render::kArchiveVersion),
                                    scene_json.value("origin", json()).dump()};
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
// JSON, the seed, the archive's key). Returns archive.json's views; their seconds go to `timings`.
json RenderViews(const BuildOptions& options, const Scene& scene, const json& scene_json, const fs::path& out,
                 const Checkpoints& checkpoints, FileHashes& hashes, const Layers& layers, const std::string& pack_key,
                 json* timings) {
  std::vector<PointCloud> world;  // as the layer files hold them
  for (const PointCloud& c : layers.clouds) world.push_back(InWorld(c));
  DensityCache densities;         // a layer's density serves every view
  json views = json::array();
  for (size_t vi = 0; vi < scene.views.size(); ++vi) {
    const SceneView& v = scene.views[vi];
    const Stopwatch watch;
    std::vector<std::string> parts = {"view", scene_json["views"][vi].dump(), scene_json.value("render", json()).dump(),
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
    r.repeat_level = scene.repeat_level;
    r.seed = scene.seed;
    r.width = scene.width;
    r.height = scene.height;
    r.size_given = true;
    r.background = scene.background;
    r.brightness = SceneBrightness(scene);
    r.opaque = v.opaque;
    r.point_size = v.point_size;
    r.mode = RenderMode::kMemory;
    r.threads = options.threads;
    RenderOutputs outputs;
    outputs.png = (out / "renders" / (v.name + ".png")).string();
    outputs.inputs = names;
    const std::string view_file = (out / "renders" / (v.name + ".view.json")).string();
    if (!v.camera_file.empty()) r.view = render::LoadView(v.camera_file);
    if (!v.camera_json.empty()) {
      WriteFileAtomic(view_file, v.camera_json + "\n");
      r.view = render::LoadView(view_file);
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
    json alphas = json::object();
    for (size_t k = 0; k < r.alpha.size(); ++k) alphas[fs::path(names[k]).stem().string()] = r.alpha[k];
    views.push_back({{"name", v.name}, {"png", "renders/" + v.name + ".png"}, {"opaque", v.opaque},
                     {"opacity", alphas}, {"resumed", checkpoint.has_value()}});
    (*timings)["views"][v.name] = seconds;
  }
  return views;
}

// 5. The COPC files the scene asks for (copc_export.h), from the layer files (key: the layers'
// keys, the scene's "copc", name, CRS and origin). Returns archive.json's "copc" (null when none
// is asked for); the seconds go to `timings`.
json WriteSceneCopc(const BuildOptions& options, const Scene& scene, const json& scene_json, const fs::path& out,
                    const Checkpoints& checkpoints, const Layers& layers, const LocalFrame& frame,
                    const std::string& scene_crs, json* timings) {
  if (!scene.copc.layers && !scene.copc.scene) return json();
  const Eigen::Vector3d& o = frame.origin;
  std::vector<std::string> parts = {"copc", scene_json["copc"].dump(), scene.name, scene_crs,
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
  if (resumed) {
    LogInfo("COPC: resumed");
  } else {
    const Stopwatch watch;
    ConsoleProgress progress("copc");
    StagedProgress closing("copc");  // each file's octree and chunks, once every point is read
    CopcOptions copc = scene.copc;
    copc.memory_bytes = options.copc_memory_bytes;
    const std::vector<CopcFile> files = WriteCopc(
        copc, source, (out / scene_file).string(),
        [&](uint64_t done, uint64_t total) {
          progress.Update(done, total);
          if (total > 0 && done >= total) progress.Finish();  // all read: the files close next
        },
        closing.Callback());
    closing.Finish();
    progress.Finish();
    json list = {{"layers", json::array()}};
    for (const CopcFile& f : files) {
      const json record = {{"path", fs::path(f.path).lexically_relative(out).generic_string()},
                           {"points", f.points}, {"bytes", f.bytes}};
      if (f.layer.empty()) {
        list["scene"] = record;
      } else {
        list["layers"].push_back(record);
        list["layers"].back()["name"] = f.layer;
      }
    }
    checkpoint = {{"seconds", watch.Seconds()}, {"files", list}};
    checkpoints.Save("copc", key, *checkpoint);
  }
  (*timings)["copc"] = checkpoint->at("seconds");
  json copc = checkpoint->at("files");
  copc["point_source_id"] = "the layer's index in \"layers\" (0-based); the files' \"candi\" VLR names them";
  copc["scale_m"] = kCopcScale;
  copc["resumed"] = resumed;
  return copc;
}

json LayersJson(const Scene& scene, FileHashes& hashes, const Layers& layers, json* timings) {
  json out = json::array();
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    const SceneLayer& l = scene.layers[k];
    json sources = json::array();
    for (const std::string& s : l.Sources()) {
      sources.push_back({{"path", s}, {"sha256", hashes(s)}, {"bytes", fs::file_size(s)}});
    }
    const Eigen::Matrix4d m = l.world_from_layer.ToMatrix();
    json matrix = json::array();
    for (int r = 0; r < 4; ++r) matrix.push_back({m(r, 0), m(r, 1), m(r, 2), m(r, 3)});
    out.push_back({{"name", l.name}, {"kind", LayerKindName(l.kind)},
                   {"scanned", l.kind == LayerKind::kPoints || l.kind == LayerKind::kPhotogrammetry},
                   {"method", layers.results[k].method}, {"parameters", layers.results[k].parameters},
                   {"sources", sources}, {"world_from_layer", matrix}, {"opacity", l.opacity},
                   {"highlight", l.highlight}, {"points", layers.clouds[k].size()}, {"dropped_nan", layers.dropped[k]},
                   {"replaces", l.replaces}, {"replaced_by", layers.replaced[k]}, {"crs", layers.crs_records[k]},
                   {"file", "layers/" + l.name + ".ply"}, {"resumed", static_cast<bool>(layers.resumed[k])}});
    (*timings)["layers"][l.name] = layers.results[k].seconds;
  }
  return out;
}

json Provenance(const Scene& scene, const LocalFrame& frame, const std::string& scene_crs, uint64_t total,
                const json& layers, bool pack_resumed, const json& views, const json& comparisons,
                const json& copc) {
  json p = {{"candi_version", kVersion}, {"scene", {{"path", scene.path}, {"sha256", Sha256Hex(scene.text)}}},
          {"name", scene.name}, {"seed", scene.seed},
          {"frame", {{"origin", {frame.origin.x(), frame.origin.y(), frame.origin.z()}}}},
          {"crs", scene_crs.empty() ? json() : json({{"definition", scene_crs}, {"label", io::CrsLabel(scene_crs)}})},
          {"points", total}, {"layers", layers}, {"archive", "archive"},
          {"pack_resumed", pack_resumed},
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
  // What a published page shows besides the layers (only when the scene gives them, so that
  // earlier scenes' archive.json keep their bytes).
  if (!scene.licence.empty()) p["licence"] = scene.licence;
  if (!scene.annotations.empty()) {
    json list = json::array();
    for (const SceneAnnotation& a : scene.annotations) {
      json e = {{"title", a.title}, {"text", a.text}, {"position", {a.position.x(), a.position.y(), a.position.z()}}};
      if (!a.view.empty()) e["view"] = a.view;
      if (!a.camera_json.empty()) e["view"] = json::parse(a.camera_json);
      list.push_back(e);
    }
    p["annotations"] = list;
  }
  if (!comparisons.empty()) p["comparisons"] = comparisons;
  if (!copc.is_null()) p["copc"] = copc;
  return p;
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
  const json scene_json = json::parse(scene.text);  // valid: LoadScene parsed it

  Layers layers;
  Box3d world_box;
  DigitizeLayers(options, scene, scene_json, out, checkpoints, hashes, &layers, &world_box);
  const LocalFrame frame = scene.origin ? LocalFrame{*scene.origin} : LocalFrame::Auto(world_box);
  std::vector<PointCloud*> digitized;
  for (LayerResult& r : layers.results) digitized.push_back(&r.cloud);
  const std::string scene_crs = CommonCrs(scene, digitized);
  PlaceLayers(scene, frame, out, &layers);
  json timings = {{"layers", json::object()}, {"views", json::object()}};  // seconds, apart from archive.json
  const json comparisons = RunComparisons(options, scene, scene_json, out, checkpoints, hashes, layers.files, &timings);
  std::string pack_key;
  const auto [pack_seconds, pack_resumed] = PackLayers(options, scene_json, out, checkpoints, layers, &pack_key);
  const json views = RenderViews(options, scene, scene_json, out, checkpoints, hashes, layers, pack_key, &timings);
  const json copc = WriteSceneCopc(options, scene, scene_json, out, checkpoints, layers, frame, scene_crs, &timings);

  // 6. MeshLab project, provenance.
  WriteMeshlab(scene, layers.clouds, (out / "meshlab").string());
  const json layers_json = LayersJson(scene, hashes, layers, &timings);
  BuildSummary summary;
  for (size_t k = 0; k < scene.layers.size(); ++k) {
    const SceneLayer& l = scene.layers[k];
    summary.layers.push_back({l.name, l.kind, layers.clouds[k].size(), l.opacity,
                              layers_json[k]["scanned"].get<bool>(), layers.results[k].seconds});
    summary.points += layers.clouds[k].size();
  }
  WriteFileAtomic((out / "archive.json").string(),
                  Provenance(scene, frame, scene_crs, summary.points, layers_json, pack_resumed, views, comparisons,
                             copc).dump(2) + "\n");
  summary.frame = frame;
  summary.views = views.size();
  auto figure = [](const json& v) { return v.is_number() ? v.get<double>() : NAN; };
  for (const json& c : comparisons) {
    summary.comparisons.push_back({c.at("name").get<std::string>(), c.at("method").get<std::string>(),
                                   c.at("count").get<uint64_t>(), figure(c.at("mean_m")), figure(c.at("rms_m")),
                                   c.at("tolerance_m").get<double>(), figure(c.at("within_tolerance")),
                                   c.at("resumed").get<bool>()});
  }
  summary.seconds = watch.Seconds();
  timings["pack"] = pack_seconds;
  timings["total"] = summary.seconds;
  WriteFileAtomic((out / "timings.json").string(), timings.dump(2) + "\n");
  return summary;
}

}  // namespace candi::pipeline

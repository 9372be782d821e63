#include "pipeline/copc_export.h"

#include <filesystem>
#include <memory>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "io/las/las_io.h"
#include "io/point_io.h"
#include "render/build_record.h"

namespace candi::pipeline {

namespace {

namespace fs = std::filesystem;

constexpr size_t kChunkPoints = 1 << 16;

// Every COPC file's points: colour and the layer's index as point source ID.
PointSchema CopcSchema() {
  PointSchema s;
  s.colors = true;
  s.scalars.push_back({io::las_field::kPointSourceId, ScalarType::kFloat32});
  return s;
}

// LAS 1.4 format 7 (colour), millimetres about the scene's origin, a fixed date (the header
// comment says why), the layers' names in a "candi" VLR; the writer adds the CRS's WKT.
PointCloudMeta CopcMeta(const CopcSource& source) {
  PointCloudMeta meta;
  meta.crs = source.crs;
  LasMetadata& las = meta.las;
  las.present = true;
  las.version_minor = 4;
  las.point_format = 7;
  las.scale = Eigen::Vector3d::Constant(kCopcScale);
  las.offset = source.origin;
  las.global_encoding = 0x10;  // WKT states the CRS (LAS 1.4, formats 6-10)
  las.creation_day = 1;
  las.creation_year = 1970;
  las.color_16bit = true;
  std::string names;
  for (size_t k = 0; k < source.layer_names.size(); ++k)
    names += std::to_string(k) + "=" + source.layer_names[k] + "\n";
  las.vlrs.push_back({"candi", kCopcLayersRecord, "scene layers: point source IDs", names, false});
  return meta;
}

// A chunk of layer `id`'s file as the COPC files hold it.
void ToCopcChunk(const PointCloud& chunk, uint16_t id, PointCloud* out) {
  out->Clear();
  out->frame = chunk.frame;
  out->Resize(chunk.size());
  for (size_t i = 0; i < chunk.size(); ++i) {
    out->positions[i] = chunk.positions[i];
    out->colors[i] = chunk.schema.colors ? chunk.colors[i] : Rgb8{180, 180, 180};
    out->scalars[0].f32[i] = id;
  }
}

// A writer's options: the records' memory budget, and Close() reporting its stages as
// "<file name> <stage>".
io::PointWriteOptions WriteOptionsFor(const std::string& path, const CopcOptions& copc,
                                      const StageProgressCallback& close_progress) {
  io::PointWriteOptions o;
  o.copc.memory_bytes = copc.memory_bytes;
  if (close_progress) {
    const std::string name = fs::path(path).filename().string();
    o.close_progress = [name, close_progress](const std::string& stage, uint64_t done,
                                              uint64_t total) {
      close_progress(name + " " + stage, done, total);
    };
  }
  return o;
}

CopcFile Closed(std::unique_ptr<io::PointWriter> writer, const std::string& path,
                const std::string& layer, uint64_t points) {
  writer->Close();
  return {path, layer, points, static_cast<uint64_t>(fs::file_size(path))};
}

// [A-Za-z0-9_-]+, and '.' too when `dot`.
bool SafeName(const std::string& name, bool dot) {
  if (name.empty()) return false;
  for (const char c : name) {
    const bool safe = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') ||
                      c == '_' || c == '-' || (dot && c == '.');
    if (!safe) return false;
  }
  return true;
}

}  // namespace

std::string SceneCopcName(const std::string& scene_name) {
  std::string name = scene_name.empty() ? "scene" : scene_name;
  for (char& c : name) {
    if (!SafeName(std::string(1, c), true)) c = '_';
  }
  return "copc/" + name + ".copc.laz";
}

std::vector<CopcFile> WriteCopc(const CopcOptions& options, const CopcSource& source,
                                const std::string& scene_file, const ProgressCallback& progress,
                                const StageProgressCallback& close_progress) {
  options.Check();
  CANDI_CHECK(source.layer_names.size() == source.layer_files.size() &&
              source.layer_names.size() < 65536)
      << "WriteCopc: " << source.layer_names.size() << " names, " << source.layer_files.size()
      << " files";
  std::vector<CopcFile> files;
  if (!options.layers && !options.scene) return files;
  const PointCloudMeta meta = CopcMeta(source);
  std::vector<std::unique_ptr<io::PointReader>> readers;
  uint64_t total = 0;
  for (const std::string& f : source.layer_files) {
    readers.push_back(io::OpenPointReader(f));
    const uint64_t n = readers.back()->info().count;
    total = n == io::kUnknownCount || total == io::kUnknownCount ? io::kUnknownCount : total + n;
  }
  std::unique_ptr<io::PointWriter> scene;
  if (options.scene) {
    const fs::path parent = fs::path(scene_file).parent_path();
    std::error_code ec;
    if (!parent.empty()) fs::create_directories(parent, ec);
    if (ec) throw InputError(scene_file, "", "cannot create its folder: " + ec.message());
    scene = io::OpenPointWriter(scene_file, {CopcSchema(), LocalFrame(), meta, total},
                                WriteOptionsFor(scene_file, options, close_progress));
  }
  PointCloud chunk, copc;
  copc.SetSchema(CopcSchema());
  uint64_t done = 0, scene_points = 0;
  for (size_t k = 0; k < readers.size(); ++k) {
    const std::string path =
        (fs::path(source.layer_files[k]).parent_path() / (source.layer_names[k] + ".copc.laz"))
            .string();
    const io::PointWriteSpec spec{CopcSchema(), LocalFrame(), meta, readers[k]->info().count};
    std::unique_ptr<io::PointWriter> layer;
    if (options.layers) layer = io::OpenPointWriter(path, spec, WriteOptionsFor(path, options, close_progress));
    uint64_t points = 0;
    while (const size_t n = readers[k]->Read(kChunkPoints, &chunk)) {
      ToCopcChunk(chunk, static_cast<uint16_t>(k), &copc);
      if (layer) layer->Write(copc);
      if (scene) scene->Write(copc);
      points += n;
      done += n;
      if (progress) progress(done, total == io::kUnknownCount ? 0 : total);
    }
    scene_points += points;
    if (layer) files.push_back(Closed(std::move(layer), path, source.layer_names[k], points));
  }
  if (scene) files.push_back(Closed(std::move(scene), scene_file, "", scene_points));
  return files;
}

CopcSource ReadCopcSource(const std::string& build_dir) {
  const fs::path dir(build_dir);
  const std::string path = (dir / render::kBuildRecord).string();
  const render::BuildRecord record = render::ReadBuildRecord(build_dir);
  CopcSource s;
  s.name = record.name;
  s.crs = record.crs_definition;
  s.origin = record.origin;
  if (record.layers.empty()) throw InputError(path, "/layers", "expected a list of layers");
  std::error_code ec;
  for (size_t k = 0; k < record.layers.size(); ++k) {
    const std::string at = "/layers/" + std::to_string(k);
    s.layer_names.push_back(record.layers[k].name);
    // It names the layer's COPC file: a scene's layer names (scene.h), nothing that leaves layers/.
    if (!SafeName(s.layer_names.back(), false)) {
      throw InputError(path, at + "/name", "not a layer name ([A-Za-z0-9_-]+)");
    }
    s.layer_files.push_back((dir / record.layers[k].file).string());
    if (!fs::exists(s.layer_files.back(), ec)) {
      throw InputError(s.layer_files.back(), "",
                       "missing: the layer file archive.json lists (" + path + ", " + at + ")");
    }
  }
  return s;
}

void CopcExportOptions::Check() const {
  CANDI_CHECK_OPTION(!build.empty(), build, "a build folder");
  CANDI_CHECK_OPTION(copc.layers || copc.scene, copc.scene,
                     "true when copc.layers is false (nothing to write)");
}

std::vector<CopcFile> ExportCopc(const CopcExportOptions& options,
                                 const ProgressCallback& progress,
                                 const StageProgressCallback& close_progress) {
  options.Check();
  const CopcSource source = ReadCopcSource(options.build);
  const std::string scene_file =
      options.out.empty() ? (fs::path(options.build) / SceneCopcName(source.name)).string()
                          : options.out;
  return WriteCopc(options.copc, source, scene_file, progress, close_progress);
}

}  // namespace candi::pipeline

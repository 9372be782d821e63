// Pieces of a build (pipeline/build.h) shared by its translation units: how each kind of layer is
// digitized (build_layers.cc), how layers are moved into the scene's frame (build_frame.cc), the
// checkpoints that let a build resume (build_checkpoints.cc) and the scene's comparisons
// (build_compare.cc). Internal to pipeline/.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/local_frame.h"
#include "core/point_cloud.h"
#include "pipeline/build.h"
#include "pipeline/scene.h"
#include "render/build_record.h"

namespace candi::pipeline::internal {

// A digitized layer: its points (world coordinates, the source's frame) and what archive.json
// says of how they were made.
struct LayerResult {
  PointCloud cloud;
  std::string method;
  nlohmann::json parameters;
  double seconds = 0;
};

// The layer digitized by its own path (build_layers.cc); intermediate files go to `work`.
LayerResult Digitize(const BuildOptions& options, const Scene& scene, const SceneLayer& layer,
                     const std::string& work);

// The layer's coordinates into the scene's CRS (scene.h, "crs"): a layer stating another CRS is
// transformed with PROJ; one stating none is taken to be in the scene's, with a warning. Points
// outside the target CRS's domain become NaN (dropped and counted by Place). Returns what
// archive.json records of the layer's CRS.
nlohmann::json ToSceneCrs(const Scene& scene, size_t k, PointCloud* cloud);
// Without a scene CRS, every layer that states one must state the same: the scene's CRS then.
std::string CommonCrs(const Scene& scene, const std::vector<PointCloud*>& clouds);
// world_from_layer, the colour override, the scene's frame; NaN positions are dropped (counted).
size_t Place(const SceneLayer& layer, uint16_t id, const LocalFrame& scene_frame, PointCloud* cloud);
// Drops the points of `target` that `by` covers (build_frame.cc says how); returns how many.
size_t ReplaceWhereCovered(const PointCloud& by, double voxel, PointCloud* target);

// Checkpoints of finished stages (pipeline/build.h, "Resuming").
class Checkpoints {
 public:
  Checkpoints(const std::filesystem::path& dir, bool resume);
  // The stage's checkpoint when resuming and its key matches (and every file in `outputs`
  // exists). Otherwise nothing, and the checkpoint is removed: the stage is about to be redone,
  // and its outputs may be replaced before its new checkpoint is written.
  std::optional<nlohmann::json> Find(const std::string& stage, const std::string& key,
                                     const std::vector<std::filesystem::path>& outputs) const;
  // Records a finished stage (after its outputs are committed).
  void Save(const std::string& stage, const std::string& key, nlohmann::json data) const;

 private:
  std::filesystem::path dir_;
  bool resume_;
};

// SHA-256 of files, each read once per build.
class FileHashes {
 public:
  const std::string& operator()(const std::string& path);

 private:
  std::map<std::string, std::string> hashes_;
};

// A folder's fingerprint for a key: every file's relative path, size and modification time (a
// dense workspace holds gigabytes of images and maps; reading them all would cost minutes).
std::string FolderFingerprint(const std::string& dir);
// A stage's key: the SHA-256 of candi's version and `parts`.
std::string Key(const std::vector<std::string>& parts);
// A digitized layer kept for a resumed build: its points (double precision, the source's frame)
// and what archive.json says of it.
void SaveLayer(const Checkpoints& checkpoints, const std::string& stage, const std::string& key,
               const std::filesystem::path& points, const LayerResult& r);
LayerResult LoadLayer(const nlohmann::json& checkpoint, const std::filesystem::path& points);

// The scene's comparisons (build_compare.cc), each the compared layer's file in `layer_files`
// (layers/<name>.ply, in scene order) against its reference, written to <out>/compare/ or
// resumed (key: the comparison's JSON, the bytes of both inputs). Returns the record's
// comparisons; each one's seconds go to (*timings)["comparisons"].
std::vector<render::BuildComparisonRecord> RunComparisons(
    const BuildOptions& options, const Scene& scene, const std::filesystem::path& out,
    const Checkpoints& checkpoints, FileHashes& hashes, const std::vector<std::string>& layer_files,
    nlohmann::json* timings);

}  // namespace candi::pipeline::internal

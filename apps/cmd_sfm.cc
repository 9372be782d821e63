// candi sfm IMAGES -o WORKSPACE: structure from motion with COLMAP (photogrammetry/colmap_runner.h).
// Prints each stage's progress on stderr, then a table (registered images, points, reprojection
// error) on stdout, and writes WORKSPACE/sfm_report.json.
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/log.h"
#include "reconstruction/photogrammetry/colmap_runner.h"

namespace candi::app {

namespace {

using photogrammetry::SfmSummary;

photogrammetry::SfmOptions Options(const SfmArgs& a) {
  photogrammetry::SfmOptions o;
  if (!a.colmap.empty()) {
    o.colmap = a.colmap;
  } else if (const char* env = std::getenv("CANDI_COLMAP"); env != nullptr && *env != '\0') {
    o.colmap = env;
  }
  o.max_image_size = a.max_image_size;
  o.max_features = a.max_features;
  o.exhaustive_max_images = a.exhaustive_max_images;
  o.camera_model = a.camera_model;
  o.single_camera = !a.camera_per_image;
  o.threads = a.threads;
  o.overwrite = a.overwrite;
  o.Check();
  return o;
}

void PrintProgress(const std::string& stage, int index, int count, double seconds, bool done) {
  if (done) {
    std::fprintf(stderr, "[sfm %d/%d] %s done in %.1f s\n", index, count, stage.c_str(), seconds);
  } else if (seconds == 0) {
    std::fprintf(stderr, "[sfm %d/%d] %s ...\n", index, count, stage.c_str());
  } else {
    std::fprintf(stderr, "[sfm %d/%d] %s running, %.0f s\n", index, count, stage.c_str(), seconds);
  }
}

nlohmann::json ToJson(const SfmSummary& s, const SfmArgs& a) {
  nlohmann::json j;
  j["colmap_version"] = s.colmap.version;
  j["cuda"] = s.colmap.cuda;
  j["images_total"] = s.images.size();
  j["images_registered"] = s.registered.size();
  j["registered"] = s.registered;
  j["ignored_files"] = s.ignored;
  j["images_without_exif"] = s.no_exif;
  j["default_focal_px"] = s.default_focal_px;
  j["points"] = s.points;
  j["mean_reprojection_error_px"] = s.mean_reprojection_error;
  j["mean_track_length"] = s.mean_track_length;
  j["matcher"] = "candi exact brute force, " + s.matcher;
  j["reproducibility"] = "image ids by photo name; exact matching (same matches every run, any thread count); "
                         "COLMAP matches_importer and mapper on one thread, random_seed 0: the same photos and "
                         "options give the same model bytes on this machine";
  j["max_image_size"] = a.max_image_size;
  j["max_features"] = a.max_features;
  j["model_dir"] = s.model_dir;
  j["dense_dir"] = s.dense_dir;
  nlohmann::json stages = nlohmann::json::object();
  for (const auto& [stage, seconds] : s.stage_seconds) stages[stage] = seconds;
  j["stage_seconds"] = stages;
  return j;
}

}  // namespace

int RunSfm(const SfmArgs& args) {
  const photogrammetry::SfmOptions options = Options(args);
  const SfmSummary s = photogrammetry::RunSfm(options, args.images, args.workspace, PrintProgress);
  if (!s.no_exif.empty()) {
    LogWarning(std::to_string(s.no_exif.size()) + " photo(s) without an EXIF focal length (e.g. " +
               s.no_exif.front() + "): COLMAP started from a guessed focal of " +
               std::to_string(static_cast<int>(s.default_focal_px)) + " px (1.2 x the longest side)" +
               (options.single_camera ? ", refined as one shared camera" : ""));
  }
  if (s.registered.size() < s.images.size()) {
    LogWarning(std::to_string(s.images.size() - s.registered.size()) + " photo(s) not registered");
  }
  double total = 0;
  for (const auto& [stage, seconds] : s.stage_seconds) total += seconds;
  std::printf("COLMAP %s (%s), %s\n", s.colmap.version.c_str(), s.colmap.cuda ? "CUDA" : "CPU",
              s.matcher.c_str());
  std::printf("%-28s %s\n", "images registered / total",
              (std::to_string(s.registered.size()) + " / " + std::to_string(s.images.size())).c_str());
  std::printf("%-28s %zu\n", "sparse points", s.points);
  std::printf("%-28s %.3f px\n", "mean reprojection error", s.mean_reprojection_error);
  std::printf("%-28s %.2f\n", "mean track length", s.mean_track_length);
  std::printf("%-28s %.1f s\n", "time", total);
  std::printf("model: %s\ndense workspace: %s\n", s.model_dir.c_str(), s.dense_dir.c_str());
  const std::string report = (std::filesystem::path(args.workspace) / "sfm_report.json").string();
  WriteFileAtomic(report, ToJson(s, args).dump(2) + "\n");
  return kOk;
}

}  // namespace candi::app

// candi relief dataset --colmap: pairs of real photographs and the depth a reconstruction gives
// them (relief_photo_pairs.h), for scoring the network on real photos (`relief eval --pairs`) and
// fine-tuning it on the visible parts of a monument (`relief train --finetune`).
//
// OUT/views/ and OUT/holdout/ hold whole pairs (photo, depth, mask) of the training and the
// held-out images; OUT/train/ and OUT/val/ the patches of the training views (the last
// val_fraction of them, by name, validate); OUT/dataset.txt says "pixels_per_m 0" (photographs
// have no metric resolution: the model keeps its own).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>
#include <stdexcept>
#include <string>

#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/colmap_model.h"
#include "reconstruction/relief/relief_dataset.h"
#include "reconstruction/relief/relief_image.h"
#include "reconstruction/relief/relief_photo_pairs.h"

namespace candi::app {

namespace {

namespace fs = std::filesystem;

// The model's images named by `holdout` (a name, a file name or a stem each); an entry that names
// none is an error, not a silently empty test set.
std::set<uint32_t> HoldoutIds(const photogrammetry::ColmapModel& model, const std::vector<std::string>& holdout) {
  std::set<uint32_t> ids;
  for (const std::string& h : holdout) {
    bool found = false;
    for (const auto& [id, image] : model.images) {
      const fs::path p(image.name);
      if (h == image.name || h == p.filename().string() || h == p.stem().string()) {
        ids.insert(id);
        found = true;
      }
    }
    if (!found) throw std::invalid_argument("--holdout '" + h + "': no such image in the COLMAP model");
  }
  return ids;
}

}  // namespace

int RunReliefPhotoDataset(const ReliefDatasetArgs& a) {
  if (a.colmap.empty() || a.images.empty()) throw std::invalid_argument("--colmap and --images go together");
  if (a.inputs.empty()) throw std::invalid_argument("give the dense cloud(s) of the model as inputs");
  relief::PhotoPairOptions options;
  options.max_side = a.max_side;
  options.Check();
  relief::PatchOptions patches;
  patches.patch = a.patch;
  patches.stride = a.stride;
  patches.Check();
  const photogrammetry::ColmapModel model = photogrammetry::ReadColmapModel(a.colmap);
  if (model.images.empty()) throw InputError(a.colmap, "", "the model has no registered images");
  const std::set<uint32_t> held = HoldoutIds(model, a.holdout);
  if (held.size() == model.images.size()) throw std::invalid_argument("--holdout holds out every image");

  std::vector<Eigen::Vector3d> points;
  for (const std::string& input : a.inputs) {
    const PointCloud cloud = io::ReadPointCloud(input);
    if (cloud.size() == 0) throw InputError(input, "", "no points");
    points.reserve(points.size() + cloud.size());
    for (size_t i = 0; i < cloud.size(); ++i) points.push_back(cloud.frame.ToWorld(cloud.positions[i]));
  }

  std::error_code ec;
  fs::create_directories(a.output_dir, ec);
  if (ec || !fs::is_directory(a.output_dir)) throw InputError(a.output_dir, "", "cannot create the output folder");
  ConsoleProgressOptions po;
  po.unit = "views";
  ConsoleProgress progress("relief dataset", po);
  std::vector<relief::PhotoPair> views;
  size_t done = 0, masked_views = 0;
  double known_sum = 0;
  for (const auto& [id, image] : model.images) {
    const auto camera = model.cameras.find(image.camera_id);
    if (camera == model.cameras.end()) {
      throw InputError(a.colmap, "image " + std::to_string(id), "camera " + std::to_string(image.camera_id) + " is missing");
    }
    const std::string photo_path = (fs::path(a.images) / image.name).string();
    relief::PhotoPair pair = relief::BuildPhotoPair(options, camera->second, image, relief::ReadPhoto(photo_path),
                                                    photo_path, points);
    size_t known = 0;
    for (uint8_t m : pair.mask.values()) known += m != 0;
    const double fraction = static_cast<double>(known) / pair.mask.values().size();
    known_sum += fraction;
    if (known == 0) {
      LogWarning(photo_path + ": the cloud covers no pixel of this view");
      ++masked_views;
    }
    const bool is_held = held.count(id) > 0;
    relief::WritePhotoPair(a.output_dir + (is_held ? "/holdout" : "/views"), pair);
    if (!is_held) views.push_back(std::move(pair));
    progress.Update(++done, model.images.size());
  }
  progress.Finish();

  const size_t n_val = views.size() > 1 ? static_cast<size_t>(std::ceil(a.val_fraction * views.size())) : 0;
  std::vector<relief::TrainingPair> train, val;
  for (size_t i = 0; i < views.size(); ++i) {
    std::vector<relief::TrainingPair> cut = relief::CutPatches(patches, {views[i].photo, views[i].depth});
    auto& to = i + n_val >= views.size() && n_val > 0 ? val : train;
    for (auto& p : cut) to.push_back(std::move(p));
  }
  if (train.empty()) {
    throw InputError(a.inputs.front(), "", "no training patch has enough known depth (views smaller than "
                                           "a patch, or a cloud that does not cover them)");
  }
  relief::WritePairs(a.output_dir + "/train", train);
  relief::WritePairs(a.output_dir + "/val", val);
  WriteFileAtomic(a.output_dir + "/dataset.txt",
                  "pixels_per_m 0\nkind photos\npatch " + std::to_string(a.patch) + "\ntrain " +
                      std::to_string(train.size()) + "\nval " + std::to_string(val.size()) + "\nviews " +
                      std::to_string(views.size()) + "\nholdout " + std::to_string(held.size()) + "\n");
  std::printf("%zu views (%zu held out) of %s, %.1f %% of their pixels with depth; %zu training and %zu "
              "validation patches of %dx%d in %s\n",
              model.images.size(), held.size(), a.colmap.c_str(), 100 * known_sum / model.images.size(),
              train.size(), val.size(), a.patch, a.patch, a.output_dir.c_str());
  if (masked_views > 0) std::printf("%zu view(s) without any depth\n", masked_views);
  return kOk;
}

}  // namespace candi::app

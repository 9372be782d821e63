#include "pipeline/relief_dataset.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"
#include "reconstruction/relief/relief_image.h"
#include "reconstruction/relief/relief_photo_pairs.h"

namespace candi::pipeline {

namespace {

namespace fs = std::filesystem;
using relief::TrainingPair;

void MakeFolder(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) throw InputError(dir, "", "cannot create the output folder");
}

// Expands folders into their *_photo.png files; other paths are kept.
std::vector<std::string> ExpandInputs(const std::vector<std::string>& inputs) {
  std::vector<std::string> out;
  for (const std::string& in : inputs) {
    std::error_code ec;
    if (!fs::is_directory(in, ec)) {
      out.push_back(in);
      continue;
    }
    std::vector<std::string> photos;
    for (const auto& e : fs::directory_iterator(in)) {
      const std::string name = e.path().filename().string();
      if (name.size() > 10 && name.compare(name.size() - 10, 10, "_photo.png") == 0) photos.push_back(e.path().string());
    }
    if (photos.empty()) throw InputError(in, "", "folder holds no *_photo.png panels");
    std::sort(photos.begin(), photos.end());
    out.insert(out.end(), photos.begin(), photos.end());
  }
  return out;
}

bool EndsWith(const std::string& s, const std::string& end) {
  return s.size() >= end.size() && s.compare(s.size() - end.size(), end.size(), end) == 0;
}

// A synthetic (or any) panel photo with its *_depth.png, resampled to pixels_per_m.
TrainingPair LoadPanel(const ReliefDatasetOptions& a, const std::string& photo_path) {
  io::PngText text;
  TrainingPair p{relief::ReadPhoto(photo_path, &text), {}};
  const std::string depth_path = photo_path.substr(0, photo_path.size() - 10) + "_depth.png";
  p.depth = relief::ReadDepth(depth_path);
  if (p.depth.width() != p.photo.width() || p.depth.height() != p.photo.height()) {
    throw InputError(depth_path, "", "size differs from its photo " + photo_path);
  }
  double ppm = p.photo.width() / a.panel_width_m;
  if (text.count("candi_pixels_per_m")) ppm = std::stod(text.at("candi_pixels_per_m"));
  const double s = a.raster.pixels_per_m / ppm;
  if (std::abs(s - 1) > 1e-6) {
    const int w = std::max(1, static_cast<int>(std::lround(p.photo.width() * s)));
    const int h = std::max(1, static_cast<int>(std::lround(p.photo.height() * s)));
    p.photo = relief::Resample(p.photo, w, h);
    p.depth = relief::Resample(p.depth, w, h);
  }
  return p;
}

TrainingPair LoadInput(const ReliefDatasetOptions& a, const std::string& path, uint64_t index) {
  if (EndsWith(path, "_photo.png")) return LoadPanel(a, path);
  relief::ScanRasterOptions o = a.raster;
  o.seed = a.raster.seed + index;
  return relief::RasterizeScan(o, io::ReadPointCloud(path), path);
}

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

// The pair with only its held-out region's pixels known (the photo whole).
relief::PhotoPair RegionOnly(const relief::PhotoPair& pair) {
  relief::PhotoPair out = pair;
  for (size_t i = 0; i < out.mask.values().size(); ++i) {
    if (out.region.values()[i] == 0) {
      out.mask.values()[i] = 0;
      out.depth.values()[i] = 0;
    }
  }
  return out;
}

uint64_t KnownPixels(const relief::PhotoPair& pair) {
  return static_cast<uint64_t>(std::count_if(pair.mask.values().begin(), pair.mask.values().end(),
                                             [](uint8_t m) { return m != 0; }));
}

// The held-out region's pixels, widened by `margin` pixels (a square window), lose their depth
// and their photo (flat grey): a training view shows nothing of the surface.
void ExcludeRegion(int margin, relief::PhotoPair* pair) {
  const int w = pair->mask.width(), h = pair->mask.height();
  Image8 rows(w, h, 1, 0), out(w, h, 1, 0);
  for (int y = 0; y < h; ++y) {  // widened along x, then along y
    for (int x = 0; x < w; ++x) {
      if (!pair->region.at(x, y)) continue;
      for (int u = std::max(0, x - margin); u <= std::min(w - 1, x + margin); ++u) rows.at(u, y) = 1;
    }
  }
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!rows.at(x, y)) continue;
      for (int v = std::max(0, y - margin); v <= std::min(h - 1, y + margin); ++v) out.at(x, v) = 1;
    }
  }
  for (size_t i = 0; i < out.values().size(); ++i) {
    if (!out.values()[i]) continue;
    pair->mask.values()[i] = 0;
    pair->depth.values()[i] = 0;
    pair->photo.values()[i] = 0.5f;
  }
}

}  // namespace

void ReliefDatasetOptions::Check() const {
  CANDI_CHECK_OPTION_GT(raster.pixels_per_m, 0);
  CANDI_CHECK_OPTION_GT(panel_width_m, 0);
  CANDI_CHECK_OPTION_IN(val_fraction, 0, 0.9);
  patches.Check();
  photo_pairs.Check();
  CANDI_CHECK_OPTION_IN(holdout_margin, 0, 64);
  if (!holdout_region.empty()) relief::ParseSceneRegion(holdout_region);  // throws naming the text
}

ReliefDatasetSummary BuildReliefDataset(const ReliefDatasetOptions& a, const std::vector<std::string>& inputs_given,
                                        const std::string& output_dir) {
  a.Check();
  const std::vector<std::string> inputs = ExpandInputs(inputs_given);
  const size_t n_val = inputs.size() > 1 ? static_cast<size_t>(std::ceil(a.val_fraction * inputs.size())) : 0;
  std::vector<TrainingPair> train, val;
  for (size_t i = 0; i < inputs.size(); ++i) {
    std::vector<TrainingPair> cut = relief::CutPatches(a.patches, LoadInput(a, inputs[i], i));
    if (cut.empty()) LogWarning(inputs[i] + ": no patch with enough valid depth");
    for (size_t k = 0; k < cut.size(); ++k) {
      // One input: every 10th patch (by val_fraction) validates; several: the last inputs do.
      const bool to_val = n_val > 0 ? i >= inputs.size() - n_val
                                    : (a.val_fraction > 0 &&
                                       (k + 1) % std::max<size_t>(2, std::lround(1 / a.val_fraction)) == 0);
      (to_val ? val : train).push_back(std::move(cut[k]));
    }
  }
  if (train.empty()) {
    throw InputError(inputs.front(), "", "no training patches (inputs smaller than a patch, or no valid depth)");
  }
  MakeFolder(output_dir);
  relief::WritePairs(output_dir + "/train", train);
  relief::WritePairs(output_dir + "/val", val);
  WriteFileAtomic(output_dir + "/dataset.txt",
                  "pixels_per_m " + FormatDouble(a.raster.pixels_per_m) + "\ndepth_m " + FormatDouble(a.raster.depth_m) +
                      "\npatch " + std::to_string(a.patches.patch) + "\ntrain " + std::to_string(train.size()) +
                      "\nval " + std::to_string(val.size()) + "\ninputs " + std::to_string(inputs.size()) + "\n");
  ReliefDatasetSummary s;
  s.train = train.size();
  s.val = val.size();
  s.inputs = inputs.size();
  return s;
}

PhotoDatasetSummary BuildPhotoDataset(const ReliefDatasetOptions& a, const std::vector<std::string>& clouds,
                                      const std::string& output_dir) {
  if (a.colmap.empty() || a.images.empty()) throw std::invalid_argument("--colmap and --images go together");
  if (clouds.empty()) throw std::invalid_argument("give the dense cloud(s) of the model as inputs");
  a.Check();
  const relief::PhotoPairOptions& options = a.photo_pairs;
  options.Check();
  const relief::PatchOptions& patches = a.patches;
  patches.Check();
  const photogrammetry::ColmapModel model = photogrammetry::ReadColmapModel(a.colmap);
  if (model.images.empty()) throw InputError(a.colmap, "", "the model has no registered images");
  const std::set<uint32_t> held = HoldoutIds(model, a.holdout);
  if (held.size() == model.images.size()) throw std::invalid_argument("--holdout holds out every image");

  std::optional<relief::SceneRegion> region;
  if (!a.holdout_region.empty()) region = relief::ParseSceneRegion(a.holdout_region);

  std::vector<Eigen::Vector3d> points;
  for (const std::string& input : clouds) {
    const PointCloud cloud = io::ReadPointCloud(input);
    if (cloud.size() == 0) throw InputError(input, "", "no points");
    points.reserve(points.size() + cloud.size());
    for (size_t i = 0; i < cloud.size(); ++i) points.push_back(cloud.frame.ToWorld(cloud.positions[i]));
  }
  std::vector<uint8_t> in_region;
  size_t region_points = 0;
  if (region) {
    in_region.resize(points.size());
    for (size_t i = 0; i < points.size(); ++i) region_points += in_region[i] = region->Contains(points[i]);
    if (region_points == 0 || region_points == points.size()) {
      throw std::invalid_argument("--holdout-region '" + a.holdout_region + "' holds " +
                                  (region_points == 0 ? "none" : "all") + " of the " + std::to_string(points.size()) +
                                  " points: nothing would be " + (region_points == 0 ? "scored" : "trained on"));
    }
    LogInfo("held-out region " + a.holdout_region + ": " + std::to_string(region_points) + " of " +
            std::to_string(points.size()) + " points");
  }

  std::error_code ec;
  fs::create_directories(output_dir, ec);
  if (ec || !fs::is_directory(output_dir)) throw InputError(output_dir, "", "cannot create the output folder");
  ConsoleProgressOptions po;
  po.unit = "views";
  ConsoleProgress progress("relief dataset", po);
  std::vector<relief::PhotoPair> views;
  size_t done = 0, masked_views = 0, region_views = 0;
  uint64_t region_pixels = 0;
  double known_sum = 0;
  for (const auto& [id, image] : model.images) {
    const auto camera = model.cameras.find(image.camera_id);
    if (camera == model.cameras.end()) {
      throw InputError(a.colmap, "image " + std::to_string(id), "camera " + std::to_string(image.camera_id) + " is missing");
    }
    const std::string photo_path = (fs::path(a.images) / image.name).string();
    relief::PhotoPair pair = relief::BuildPhotoPair(options, camera->second, image, relief::ReadPhoto(photo_path),
                                                    photo_path, points, region ? &in_region : nullptr);
    size_t known = 0;
    for (uint8_t m : pair.mask.values()) known += m != 0;
    const double fraction = static_cast<double>(known) / pair.mask.values().size();
    known_sum += fraction;
    if (known == 0) {
      LogWarning(photo_path + ": the cloud covers no pixel of this view");
      ++masked_views;
    }
    const bool is_held = held.count(id) > 0;
    if (region) {
      const relief::PhotoPair scored = RegionOnly(pair);
      const uint64_t pixels = KnownPixels(scored);
      if (pixels > 0) relief::WritePhotoPair(output_dir + "/holdout", scored);
      region_pixels += pixels;
      if (pixels > 0) ++region_views;
      if (!is_held) {
        ExcludeRegion(a.holdout_margin, &pair);
        relief::WritePhotoPair(output_dir + "/views", pair);
        views.push_back(std::move(pair));
      }
    } else {
      relief::WritePhotoPair(output_dir + (is_held ? "/holdout" : "/views"), pair);
      if (!is_held) views.push_back(std::move(pair));
    }
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
    throw InputError(clouds.front(), "", "no training patch has enough known depth (views smaller than "
                                           "a patch, or a cloud that does not cover them)");
  }
  relief::WritePairs(output_dir + "/train", train);
  relief::WritePairs(output_dir + "/val", val);
  WriteFileAtomic(output_dir + "/dataset.txt",
                  "pixels_per_m 0\nkind photos\npatch " + std::to_string(a.patches.patch) + "\ntrain " +
                      std::to_string(train.size()) + "\nval " + std::to_string(val.size()) + "\nviews " +
                      std::to_string(views.size()) + "\nholdout " + std::to_string(held.size()) +
                      (region ? "\nholdout_region " + a.holdout_region + "\nholdout_region_views " +
                                    std::to_string(region_views) + "\nholdout_region_pixels " + std::to_string(region_pixels)
                              : std::string()) + "\n");
  PhotoDatasetSummary s;
  s.views = model.images.size();
  s.held_out = held.size();
  s.region_views = region_views;
  s.region_pixels = region_pixels;
  s.known_fraction = known_sum / model.images.size();
  s.train = train.size();
  s.val = val.size();
  s.empty_views = masked_views;
  return s;
}

}  // namespace candi::pipeline

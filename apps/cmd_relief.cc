// candi relief synth | dataset | predict | points: the buried-relief path from photo to points
// (reconstruction/relief). Outputs are written atomically; bad inputs are InputError (exit 2).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "io/point_io.h"
#include "reconstruction/relief/relief_dataset.h"
#include "reconstruction/relief/relief_image.h"
#include "reconstruction/relief/relief_net.h"
#include "reconstruction/relief/relief_points.h"
#include "reconstruction/relief/relief_synth.h"

namespace candi::app {

namespace {

namespace fs = std::filesystem;
using relief::TrainingPair;

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void MakeFolder(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) throw InputError(dir, "", "cannot create the output folder");
}

std::string PanelName(const std::string& dir, int i, const char* kind) {
  char name[64];
  std::snprintf(name, sizeof(name), "/panel_%04d_%s.png", i, kind);
  return dir + name;
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
TrainingPair LoadPanel(const ReliefDatasetArgs& a, const std::string& photo_path) {
  io::PngText text;
  TrainingPair p{relief::ReadPhoto(photo_path, &text), {}};
  const std::string depth_path = photo_path.substr(0, photo_path.size() - 10) + "_depth.png";
  p.depth = relief::ReadDepth(depth_path);
  if (p.depth.width() != p.photo.width() || p.depth.height() != p.photo.height()) {
    throw InputError(depth_path, "", "size differs from its photo " + photo_path);
  }
  double ppm = p.photo.width() / a.panel_width_m;
  if (text.count("candi_pixels_per_m")) ppm = std::stod(text.at("candi_pixels_per_m"));
  const double s = a.pixels_per_m / ppm;
  if (std::abs(s - 1) > 1e-6) {
    const int w = std::max(1, static_cast<int>(std::lround(p.photo.width() * s)));
    const int h = std::max(1, static_cast<int>(std::lround(p.photo.height() * s)));
    p.photo = relief::Resample(p.photo, w, h);
    p.depth = relief::Resample(p.depth, w, h);
  }
  return p;
}

TrainingPair LoadInput(const ReliefDatasetArgs& a, const std::string& path, uint64_t index) {
  if (EndsWith(path, "_photo.png")) return LoadPanel(a, path);
  relief::ScanRasterOptions o;
  o.pixels_per_m = a.pixels_per_m;
  o.frame = a.frame;
  o.depth_m = a.depth_m;
  o.relight = !a.no_relight;
  o.seed = a.seed + index;
  return relief::RasterizeScan(o, io::ReadPointCloud(path), path);
}

}  // namespace

int RunReliefSynth(const ReliefSynthArgs& a) {
  relief::SynthOptions o;
  o.width = a.width;
  o.width_m = a.width_m, o.height_m = a.height_m, o.depth_m = a.depth_m;
  o.seed = a.seed;
  o.photo.shadows = !a.no_shadows, o.photo.stains = !a.no_stains, o.photo.blur = !a.no_blur;
  o.photo.grain = !a.no_grain, o.photo.tone = !a.no_tone, o.photo.fading = !a.no_fading;
  o.Check();
  MakeFolder(a.output_dir);
  ConsoleProgressOptions po;
  po.unit = "panels";
  ConsoleProgress progress("relief synth", po);
  for (int i = 0; i < a.count; ++i) {
    const relief::SynthPanel p = relief::SynthesizePanel(o, static_cast<uint64_t>(i));
    const io::PngText text = {
        {"candi_seed", std::to_string(a.seed)}, {"candi_panel", std::to_string(i)},
        {"candi_pixels_per_m", FormatDouble(1.0 / p.pixel_m)},
        {"candi_depth_m", FormatDouble(a.depth_m)},
        {"candi_light_azimuth_deg", FormatDouble(p.photo.light_azimuth_deg)},
        {"candi_light_elevation_deg", FormatDouble(p.photo.light_elevation_deg)}};
    relief::WritePhoto(PanelName(a.output_dir, i, "photo"), p.photo.photo, text);
    relief::WriteDepth16(PanelName(a.output_dir, i, "depth"), p.depth, text);
    progress.Update(i + 1, a.count);
  }
  progress.Finish();
  std::printf("%d panels %dx%d (%.4g mm/pixel) in %s\n", a.count, o.width, o.Height(),
              1000 * o.PixelM(), a.output_dir.c_str());
  return kOk;
}

int RunReliefDataset(const ReliefDatasetArgs& a) {
  if (!a.colmap.empty() || !a.images.empty()) return RunReliefPhotoDataset(a);
  if (!(a.pixels_per_m > 0) || !(a.panel_width_m > 0)) {
    throw std::invalid_argument("--pixels-per-m and --panel-width-m must be > 0");
  }
  relief::PatchOptions patches;
  patches.patch = a.patch;
  patches.stride = a.stride;
  patches.Check();
  const std::vector<std::string> inputs = ExpandInputs(a.inputs);
  const size_t n_val = inputs.size() > 1 ? static_cast<size_t>(std::ceil(a.val_fraction * inputs.size())) : 0;
  std::vector<TrainingPair> train, val;
  for (size_t i = 0; i < inputs.size(); ++i) {
    std::vector<TrainingPair> cut = relief::CutPatches(patches, LoadInput(a, inputs[i], i));
    if (cut.empty()) LogWarning(inputs[i] + ": no patch with enough valid depth");
    for (size_t k = 0; k < cut.size(); ++k) {
      // One input: every 10th patch (by val_fraction) validates; several: the last inputs do.
      const bool to_val = n_val > 0 ? i >= inputs.size() - n_val
                                    : (a.val_fraction > 0 && (k + 1) % std::max<size_t>(2, std::lround(1 / a.val_fraction)) == 0);
      (to_val ? val : train).push_back(std::move(cut[k]));
    }
  }
  if (train.empty()) throw InputError(inputs.front(), "", "no training patches (inputs smaller than a patch, or no valid depth)");
  MakeFolder(a.output_dir);
  relief::WritePairs(a.output_dir + "/train", train);
  relief::WritePairs(a.output_dir + "/val", val);
  WriteFileAtomic(a.output_dir + "/dataset.txt",
                  "pixels_per_m " + FormatDouble(a.pixels_per_m) + "\ndepth_m " + FormatDouble(a.depth_m) +
                      "\npatch " + std::to_string(a.patch) + "\ntrain " + std::to_string(train.size()) +
                      "\nval " + std::to_string(val.size()) + "\ninputs " + std::to_string(inputs.size()) + "\n");
  std::printf("%zu training and %zu validation pairs of %dx%d from %zu inputs in %s\n", train.size(),
              val.size(), a.patch, a.patch, inputs.size(), a.output_dir.c_str());
  return kOk;
}

bool ReliefInProcess() { return true; }

int RunReliefPredict(const ReliefPredictArgs& a) {
  relief::PredictOptions o;
  o.tiles.tile = a.tile;
  o.tiles.overlap = a.overlap;
  o.Check();
  if (a.width_m < 0) throw std::invalid_argument("--width-m must be >= 0");
  relief::SetTorchThreads(a.threads);
  const relief::DepthModel model = relief::DepthModel::Load(a.model);
  const ImageF photo = relief::ReadPhoto(a.photo);
  o.photo_pixels_per_m = a.width_m > 0 ? photo.width() / a.width_m : 0;
  const auto t0 = std::chrono::steady_clock::now();
  ConsoleProgressOptions po;
  po.unit = "tiles";
  ConsoleProgress progress("relief predict", po);
  const ImageF depth = model.Predict(o, photo, progress.Callback());
  progress.Finish();
  const double seconds = Seconds(t0);
  relief::WriteDepth8(a.output, depth, {{"candi_model", a.model}});
  if (!a.output16.empty()) relief::WriteDepth16(a.output16, depth, {{"candi_model", a.model}});
  std::printf("depth %dx%d of %s in %.2f s (%d thread(s)) -> %s\n", depth.width(), depth.height(),
              a.photo.c_str(), seconds, a.threads, a.output.c_str());
  return kOk;
}

int RunReliefPoints(const ReliefPointsArgs& a) {
  relief::ReliefPointsOptions o;
  o.width_m = a.width_m, o.height_m = a.height_m, o.depth_m = a.depth_m;
  o.Check();
  io::OutputPointFormat(a.output);  // a known extension before any work
  const auto t0 = std::chrono::steady_clock::now();
  const ImageF photo = relief::ReadPhoto(a.photo);
  const ImageF depth = relief::ReadDepth(a.depth);
  if (photo.width() != depth.width() || photo.height() != depth.height()) {
    throw InputError(a.depth, "", "depth map is " + std::to_string(depth.width()) + "x" +
                                      std::to_string(depth.height()) + ", photo " + a.photo + " is " +
                                      std::to_string(photo.width()) + "x" + std::to_string(photo.height()));
  }
  PointCloud cloud = relief::DepthToPoints(o, photo, depth);
  cloud.meta.comments.push_back("candi_relief_points frame=panel width_m=" + FormatDouble(o.width_m) +
                                " height_m=" + FormatDouble(o.height_m) + " depth_m=" + FormatDouble(o.depth_m));
  io::WritePointCloud(a.output, cloud);
  std::printf("%zu points (%dx%d pixels, %.4g x %.4g x %.4g m) in %.2f s -> %s\n", cloud.size(),
              depth.width(), depth.height(), o.width_m, o.height_m, o.depth_m, Seconds(t0), a.output.c_str());
  return kOk;
}

}  // namespace candi::app

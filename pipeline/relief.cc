#include "pipeline/relief.h"

#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "core/check.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "core/timer.h"
#include "io/point_io.h"
#include "reconstruction/relief/relief_image.h"

namespace candi::pipeline {

namespace {

std::string PanelName(const std::string& dir, int i, const char* kind) {
  char name[64];
  std::snprintf(name, sizeof(name), "/panel_%04d_%s.png", i, kind);
  return dir + name;
}

}  // namespace

void WriteSyntheticPanels(const relief::SynthOptions& o, int count, const std::string& dir) {
  o.Check();
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) throw InputError(dir, "", "cannot create the output folder");
  ConsoleProgressOptions po;
  po.unit = "panels";
  ConsoleProgress progress("relief synth", po);
  for (int i = 0; i < count; ++i) {
    const relief::SynthPanel p = relief::SynthesizePanel(o, static_cast<uint64_t>(i));
    const io::PngText text = {{"candi_seed", std::to_string(o.seed)},
                              {"candi_panel", std::to_string(i)},
                              {"candi_pixels_per_m", FormatDouble(1.0 / p.pixel_m)},
                              {"candi_depth_m", FormatDouble(o.depth_m)},
                              {"candi_light_azimuth_deg", FormatDouble(p.photo.light_azimuth_deg)},
                              {"candi_light_elevation_deg", FormatDouble(p.photo.light_elevation_deg)}};
    relief::WritePhoto(PanelName(dir, i, "photo"), p.photo.photo, text);
    relief::WriteDepth16(PanelName(dir, i, "depth"), p.depth, text);
    progress.Update(i + 1, count);
  }
  progress.Finish();
}

void PanelDepthOptions::Check() const {
  predict.Check();
  CANDI_CHECK_OPTION(width_m >= 0 && std::isfinite(width_m), width_m, "finite and >= 0 (0: the model's resolution)");
  CANDI_CHECK_OPTION_IN(threads, 1, 256);
}

PanelDepth PredictPanelDepth(const PanelDepthOptions& options, const std::string& photo_path,
                             const std::string& model_path) {
  options.Check();
  relief::SetTorchThreads(options.threads);
  const relief::DepthModel model = relief::DepthModel::Load(model_path);
  const ImageF photo = relief::ReadPhoto(photo_path);
  relief::PredictOptions o = options.predict;
  o.photo_pixels_per_m = options.width_m > 0 ? photo.width() / options.width_m : 0;
  const Stopwatch watch;
  ConsoleProgressOptions po;
  po.unit = "tiles";
  ConsoleProgress progress("relief predict", po);
  PanelDepth out;
  out.depth = model.Predict(o, photo, progress.Callback());
  progress.Finish();
  out.seconds = watch.Seconds();
  return out;
}

void WritePanelDepth(const ImageF& depth, const std::string& model, const std::string& png8,
                     const std::string& png16) {
  relief::WriteDepth8(png8, depth, {{"candi_model", model}});
  if (!png16.empty()) relief::WriteDepth16(png16, depth, {{"candi_model", model}});
}

PanelPoints PanelPointsOf(const relief::ReliefPointsOptions& o, const std::string& photo_path,
                          const std::string& depth_png) {
  o.Check();
  const ImageF photo = relief::ReadPhoto(photo_path);
  const ImageF depth = relief::ReadDepth(depth_png);
  if (photo.width() != depth.width() || photo.height() != depth.height()) {
    throw InputError(depth_png, "", "depth map is " + std::to_string(depth.width()) + "x" +
                                        std::to_string(depth.height()) + ", photo " + photo_path + " is " +
                                        std::to_string(photo.width()) + "x" + std::to_string(photo.height()));
  }
  PanelPoints out;
  out.cloud = relief::DepthToPoints(o, photo, depth);
  out.cloud.meta.comments.push_back("candi_relief_points frame=panel width_m=" + FormatDouble(o.width_m) +
                                    " height_m=" + FormatDouble(o.height_m) + " depth_m=" + FormatDouble(o.depth_m));
  out.width = depth.width();
  out.height = depth.height();
  return out;
}

ReliefPanelRunner ReliefInProcess() {
  return [](const ReliefPanelJob& job) {
    PanelDepthOptions predict;
    predict.width_m = job.predict_width_m;
    predict.threads = 2;
    const PanelDepth depth = PredictPanelDepth(predict, job.photo, job.model);
    WritePanelDepth(depth.depth, job.model, job.depth, "");
    relief::ReliefPointsOptions points;
    points.width_m = job.width_m;
    io::WritePointCloud(job.points, PanelPointsOf(points, job.photo, job.depth).cloud);
  };
}

}  // namespace candi::pipeline

#include "pipeline/render.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <optional>
#include <stdexcept>

#include "core/check.h"
#include "core/log.h"
#include "core/mapped_file.h"
#include "core/text_format.h"
#include "core/version.h"
#include "io/point_io.h"
#include "io/point_records.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"
#include "render/archive_render.h"
#include "render/legend.h"
#include "render/spbr_stream.h"
#include "render/splat_cloud.h"
#include "render/view_json.h"
#include "sampling/opacity.h"

namespace candi::pipeline {

namespace {

// Points above which RenderMode::kAuto streams: files whose records are drawn in place stream
// faster than a splat cloud is prepared (2·10^6 points: 0.12 s against 0.21 s; 2·10^7: 0.47 s
// against 1.43 s, bench/first_image_bench) and in less memory; others from 5·10^7.
constexpr uint64_t kStreamThreshold = 50000000;
constexpr uint64_t kStreamInPlaceThreshold = 1000000;

// The camera in world coordinates: the view given, or one that frames the data (clipped).
render::Camera WorldCamera(const RenderOptions& o, const Box3d& world) {
  if (o.view) {
    render::Camera c = *o.view;
    if (o.size_given) c.width = o.image.width, c.height = o.image.height;
    return c;
  }
  return render::FirstView(ClippedBounds(world, o.clip), o.image.width, o.image.height,
                           o.orientation);
}

render::Camera InFrame(render::Camera c, const LocalFrame& frame) {
  c.eye -= frame.origin;
  c.target -= frame.origin;
  return c;
}

// Opacity control for cloud k (ALGORITHMS.md §1): the pixel footprint s is the camera's at its
// target, so the law is met where the view is focused.
void AdjustCloud(const RenderOptions& o, const render::Camera& world_camera, size_t k, const std::string& name,
                 const std::string& density_key, DensityCache* cache, PointCloud* cloud) {
  sampling::OpacityOptions opacity;
  opacity.alpha = o.alpha.size() == 1 ? o.alpha[0] : o.alpha[k];
  opacity.spbr = o.image.spbr;
  opacity.image_size = 0;
  opacity.pixel_size = world_camera.PixelFootprint((world_camera.target - world_camera.eye).norm());
  opacity.density.threads = o.threads;
  sampling::OpacityResult r = sampling::AdjustOpacity(opacity, *cloud, cache->Get(density_key, opacity, *cloud));
  LogInfo(name + ": opacity " + FormatDouble(opacity.alpha) + " at pixel " + FormatDouble(opacity.pixel_size) +
          " m: " + std::to_string(r.summary.points_in) + " points -> " + std::to_string(r.summary.total_copies) +
          " copies (predicted alpha " + FormatDouble(r.summary.predicted_alpha) + ")");
  if (!r.summary.message.empty()) LogInfo(name + ": " + r.summary.message);
  *cloud = std::move(r.cloud);
}

// Draws clouds that are the caller's to change (opacity control and clipping replace them).
RenderedImage RenderOwnedClouds(const RenderOptions& o, std::vector<PointCloud>* clouds,
                                const std::vector<std::string>& names, const std::vector<std::string>& density_keys,
                                DensityCache* cache) {
  uint64_t total = 0;
  Box3d world;
  for (const PointCloud& c : *clouds) {
    total += c.size();
    if (!c.empty()) world.Extend(c.WorldBounds());
  }
  if (total == 0) throw InputError("nothing to render: the inputs hold no points");
  RenderedImage image;
  image.mode = "memory";
  image.world_camera = WorldCamera(o, world);
  if (o.colour_by.active()) {  // one legend over every input, before opacity control copies points
    std::vector<std::vector<double>> values;
    std::vector<const std::vector<double>*> pointers;
    for (size_t k = 0; k < clouds->size(); ++k) values.push_back(FieldValues((*clouds)[k], o.colour_by.field, names[k]));
    for (const auto& v : values) pointers.push_back(&v);
    image.legend = ResolveFieldColouring(o.colour_by, pointers);
    for (size_t k = 0; k < clouds->size(); ++k) ColourByField(*image.legend, values[k], &(*clouds)[k]);
    LogInfo("coloured by " + o.colour_by.field + " (" + FieldScaleName(image.legend->scale) + ", " +
            FormatDouble(image.legend->lo) + " to " + FormatDouble(image.legend->hi) + "): " +
            std::to_string(image.legend->outside) + " points outside the range, " +
            std::to_string(image.legend->undefined) + " undefined (grey)");
  }
  // Opacity control sees the whole cloud (its density does not depend on the clipping); the
  // clipping then removes points, as the archive renderer skips them.
  for (size_t k = 0; k < clouds->size() && !o.alpha.empty(); ++k) {
    AdjustCloud(o, image.world_camera, k, names[k], density_keys[k], cache, &(*clouds)[k]);
  }
  for (PointCloud& c : *clouds) ClipCloud(o.clip, &c);
  std::vector<const PointCloud*> pointers;
  for (const PointCloud& c : *clouds) pointers.push_back(&c);
  render::SplatCloudOptions build;
  build.spbr = o.image.spbr;
  ConsoleProgress building("render: preparing " + std::to_string(total) + " points");
  const render::SplatCloud splats = render::BuildSplatCloud(build, pointers, building.Callback());
  building.Finish();
  clouds->clear();
  if (splats.copies() == 0) LogInfo("every point was removed (alpha 0): the image shows the background");
  render::SpbrOptions spbr;
  spbr.ensembles = o.preview;
  spbr.threads = o.threads;
  ConsoleProgressOptions po;
  po.unit = "ensembles";
  ConsoleProgress progress("render: SPBR L=" + std::to_string(o.image.spbr.EffectiveRepeatLevel()),
                           po);
  image.result = render::RenderSpbr(spbr, InFrame(image.world_camera, splats.frame), splats, progress.Callback());
  progress.Finish();
  return image;
}

RenderedImage RenderFilesInMemory(const RenderOptions& o, const std::vector<std::string>& files) {
  std::vector<PointCloud> clouds;
  io::PointReadOptions read;
  read.columns = o.columns;
  for (const std::string& in : files) {
    // Scalar fields are decoded only where the render uses one: the field coloured by, or the
    // points' multiplicities (render/splat_cloud.h). (LAS attributes cost more than positions.)
    const PointSchema schema = io::OpenPointReader(in, read)->info().schema;
    io::PointReadOptions file_read = read;
    file_read.scalar_fields = o.colour_by.active() || schema.ScalarIndex(render::kMultiplicityField) >= 0;
    clouds.push_back(io::ReadPointCloud(in, file_read));
  }
  const std::vector<std::string>& keys = files;  // a file given twice has one density
  DensityCache cache;
  return RenderOwnedClouds(o, &clouds, files, keys, &cache);
}

// The inputs' world bounds and point count: from a pass over the records in place, in parallel,
// where a file's points are records (io/point_records.h; a LAS header's bounds are not trusted
// then: the first view frames the points, as in memory mode); else from the header's bounds when
// every other input states them (LAZ), else from a pass over the reader's chunks.
Box3d StreamBounds(const std::vector<std::string>& files, const io::PointReadOptions& read, uint64_t* total) {
  Box3d world;
  *total = 0;
  std::vector<std::string> others;  // inputs whose points are not records read in place
  for (const std::string& in : files) {
    auto r = io::OpenPointReader(in, read);
    if (const std::optional<io::PointRecordLayout> layout = r->record_layout()) {
      const MappedFile map(in);
      if (const std::optional<Box3d> box = io::RecordBounds(map, *layout)) {
        world.Extend(box->Translated(r->info().frame.origin));
        *total += layout->count;
        continue;
      }  // else the reader says what is wrong with the file
    }
    others.push_back(in);
  }
  bool all_headers = true;
  Box3d headers = world;
  uint64_t counted = *total;
  for (const std::string& in : others) {
    auto r = io::OpenPointReader(in, read);
    if (r->info().header_bounds) headers.Extend(*r->info().header_bounds); else all_headers = false;
    if (r->info().count != io::kUnknownCount) counted += r->info().count;
  }
  if (all_headers) {
    *total = counted;
    return headers;
  }
  ConsoleProgress progress("render: bounds");
  for (const std::string& in : others) {
    auto r = io::OpenPointReader(in, read);
    const uint64_t before = *total;
    const io::PointScan scan = io::ScanPoints(*r, [&](uint64_t done, uint64_t) { progress.Update(before + done, 0); });
    world.Extend(scan.world);
    *total += scan.count;
  }
  return world;
}

// Feeds one file's points to the renderer: records in place where the file's points are records,
// no clip removes points and none has a multiplicity (the same image as its chunks give), else
// the reader's chunks (with the multiplicities, when drawn).
void StreamFile(const RenderOptions& o, const std::string& in, io::PointReadOptions read,
                render::SpbrStreamRenderer* renderer, const std::function<void(uint64_t)>& advance) {
  io::PointReadOptions all = read;
  all.scalar_fields = true;
  auto r = io::OpenPointReader(in, all);
  const bool multiplicity =
      !o.image.spbr.opaque && r->info().schema.ScalarIndex(render::kMultiplicityField) >= 0;
  if (!multiplicity) r = io::OpenPointReader(in, read);
  if (const std::optional<io::PointRecordLayout> layout = r->record_layout(); layout && o.clip.empty() && !multiplicity) {
    const MappedFile map(in);
    if (io::HoldsRecords(map, *layout)) {
      constexpr uint64_t kRound = uint64_t{1} << 22;  // records staged at a time
      for (uint64_t at = 0; at < layout->count; at += kRound) {
        const size_t n = static_cast<size_t>(std::min(kRound, layout->count - at));
        const uint64_t byte = layout->first_byte + at * layout->stride;
        map.CheckSize(byte + n * layout->stride, "point records");  // a file that shrank: an error, not SIGBUS
        map.WillNeed(byte + n * layout->stride, kRound * layout->stride);
        renderer->AddRecords(map.data() + byte, *layout, r->info().frame.origin, n);
        advance(n);
      }
      return;
    }
  }
  PointCloud chunk;
  while (r->Read(1 << 20, &chunk) > 0) {
    const size_t n = chunk.size();
    ClipCloud(o.clip, &chunk);
    renderer->Add(chunk);
    advance(n);
  }
}

RenderedImage RenderFilesStreaming(const RenderOptions& o, const std::vector<std::string>& files) {
  io::PointReadOptions read;
  read.columns = o.columns;
  read.scalar_fields = false;  // geometry and colour (and multiplicities: StreamFile)
  uint64_t total = 0;
  const Box3d world = StreamBounds(files, read, &total);
  if (total == 0 || world.IsEmpty()) throw InputError("nothing to render: the inputs hold no points");
  const LocalFrame frame = render::RenderFrameFor(world);
  RenderedImage image;
  image.mode = "stream";
  image.world_camera = WorldCamera(o, world);
  if (image.world_camera.projection != render::Projection::kPerspective) {
    throw std::invalid_argument("--mode stream draws perspective views; use --mode memory for orthographic views");
  }
  render::SpbrStreamOptions so;
  so.spbr = o.image.spbr;
  so.threads = o.threads;
  so.memory_budget = o.memory_budget;
  so.expected_points = total;  // few enough: gathered by ensemble, no L z-buffers held
  render::SpbrStreamRenderer renderer(so, InFrame(image.world_camera, frame), frame);
  ConsoleProgress progress("render: SPBR L=" + std::to_string(o.image.spbr.EffectiveRepeatLevel()) +
                           " streaming, " + std::to_string(renderer.passes()) + " pass(es)");
  uint64_t done = 0;
  for (int pass = 0; pass < renderer.passes(); ++pass) {
    renderer.BeginPass(pass);
    for (const std::string& in : files) {
      StreamFile(o, in, read, &renderer, [&](uint64_t n) {
        done += n;
        progress.Update(done, total * renderer.passes());
      });
    }
    renderer.EndPass();
  }
  progress.Finish();
  image.result = renderer.Finish();
  return image;
}

bool Streams(const RenderOptions& o, const std::vector<std::string>& files) {
  if (o.mode != RenderMode::kAuto) return o.mode == RenderMode::kStream;
  if (!o.alpha.empty() || o.colour_by.active() || o.preview > 0) return false;
  if (o.view && o.view->projection != render::Projection::kPerspective) return false;  // stream: perspective only
  uint64_t stated = 0;
  bool in_place = o.clip.empty();  // every input's points drawn from its records (StreamFile)
  for (const std::string& in : files) {
    io::PointReadOptions read;
    read.columns = o.columns;
    const auto r = io::OpenPointReader(in, read);
    const uint64_t count = r->info().count;
    if (count != io::kUnknownCount) stated += count;
    in_place &=
        r->record_layout() &&
        (o.image.spbr.opaque || r->info().schema.ScalarIndex(render::kMultiplicityField) < 0);
  }
  return stated > (in_place ? kStreamInPlaceThreshold : kStreamThreshold);
}

}  // namespace

void RenderOptions::Check() const {
  image.Check();
  for (double a : alpha) CANDI_CHECK_OPTION(a >= 0 && a <= 1, alpha, "in [0, 1] (each)");
  CANDI_CHECK_OPTION(!(image.spbr.opaque && !alpha.empty()), image.spbr.opaque,
                     "false when alpha is given (they exclude each other)");
  CANDI_CHECK_OPTION(!(mode == RenderMode::kStream && !alpha.empty()), alpha,
                     "empty in stream mode (opacity control needs the whole cloud)");
  CANDI_CHECK_OPTION(!(mode == RenderMode::kStream && preview > 0), preview,
                     "0 in stream mode (it draws every ensemble)");
  colour_by.Check();
  if (mode == RenderMode::kStream && colour_by.active()) {
    throw std::invalid_argument("colouring by a field needs memory mode: stream mode reads no scalar fields");
  }
  CANDI_CHECK_OPTION_IN(threads, 0, 256);
  CANDI_CHECK_OPTION_GE(preview, 0);
  CANDI_CHECK_OPTION_GT(memory_budget, 0);
  CANDI_CHECK_OPTION_GT(chunk_budget, 0);
  for (const auto& [name, share] : layer_shares) {
    if (!(share >= 0 && share <= 16)) {
      throw std::invalid_argument("RenderOptions::layer_shares[" + name + "] = " + FormatDouble(share) +
                                  "; must be in [0, 16]");
    }
  }
}

render::Orientation OrientationOfCameras(const std::string& colmap_model) {
  const photogrammetry::ColmapModel model = photogrammetry::ReadColmapModel(colmap_model);
  Eigen::Vector3d down = Eigen::Vector3d::Zero(), forward = Eigen::Vector3d::Zero();
  for (const auto& [id, image] : model.images) {
    const Eigen::Matrix3d world_from_cam = image.cam_from_world_rotation.toRotationMatrix().transpose();
    down += world_from_cam.col(1);
    forward += world_from_cam.col(2);
  }
  if (model.images.empty() || !(down.norm() > 1e-6 * model.images.size())) {
    throw InputError(colmap_model, "", "no registered images (or their up directions cancel out): cannot orient a view");
  }
  render::Orientation o;
  o.up = -down.normalized();
  // Looking the cameras' way, tilted to be square to up (an oblique mean would tilt the view).
  const Eigen::Vector3d level = forward - forward.dot(o.up) * o.up;
  if (level.norm() > 1e-6 * std::max(1.0, forward.norm())) o.view_dir = level.normalized();
  LogInfo("view oriented by the " + std::to_string(model.images.size()) + " cameras of " + colmap_model);
  return o;
}

const sampling::DensityResult& DensityCache::Get(const std::string& key, const sampling::OpacityOptions& options,
                                                 const PointCloud& cloud) {
  auto it = densities_.find(key);
  if (it == densities_.end() || it->second.density.size() != cloud.size()) {
    it = densities_.insert_or_assign(key, sampling::OpacityDensity(options, cloud)).first;
  }
  return it->second;
}

RenderedImage RenderPointFiles(const RenderOptions& o, const std::vector<std::string>& files) {
  o.Check();
  return Streams(o, files) ? RenderFilesStreaming(o, files) : RenderFilesInMemory(o, files);
}

RenderedImage RenderClouds(const RenderOptions& o, const std::vector<const PointCloud*>& clouds,
                           const std::vector<std::string>& names, const std::vector<std::string>& density_keys,
                           DensityCache* cache) {
  o.Check();
  CANDI_CHECK(names.size() == clouds.size() && density_keys.size() == clouds.size() && cache != nullptr);
  std::vector<PointCloud> copies;
  for (const PointCloud* c : clouds) copies.push_back(*c);
  return RenderOwnedClouds(o, &copies, names, density_keys, cache);
}

RenderedImage RenderArchiveEnsembles(const RenderOptions& o, const render::Archive& archive, int rank, int ranks) {
  o.Check();
  if (!o.alpha.empty()) {
    throw std::invalid_argument("--alpha needs point files: an archive holds one copy per point");
  }
  if (o.colour_by.active()) {
    throw std::invalid_argument("colouring by a field needs point files: an archive holds the points' colours, "
                                "not their fields (candi pack --colour-by packs them coloured)");
  }
  const render::ArchiveManifest& m = archive.manifest();
  RenderedImage image;
  image.legend = m.colour_by;  // packed coloured by a field: the image carries its legend
  image.mode = ranks > 1 ? "archive, MPI" : "archive";
  image.world_camera = WorldCamera(o, m.bounds.Translated(m.frame.origin));
  const int repeat_level = o.image.spbr.EffectiveRepeatLevel();
  const int drawn = o.preview > 0 ? std::min(o.preview, repeat_level) : repeat_level;
  render::ArchiveRenderOptions ao;
  ao.spbr = o.image.spbr;
  ao.threads = o.threads;
  ao.memory_budget = o.memory_budget;
  ao.chunk_budget = o.chunk_budget;
  ao.clip = o.clip.ToLocal(m.frame.origin);
  if (!o.layer_shares.empty()) {
    ao.layer_fraction.assign(m.layers.size(), 1.0);
    for (const auto& [name, share] : o.layer_shares) {
      const auto it = std::find_if(m.layers.begin(), m.layers.end(),
                                   [&](const render::ArchiveLayer& l) { return l.name == name; });
      if (it == m.layers.end()) throw std::invalid_argument("the view's layer '" + name + "' is not in the archive");
      ao.layer_fraction[it - m.layers.begin()] = share;
    }
  }
  render::EnsembleShare(drawn, rank, ranks, &ao.ensemble_begin, &ao.ensemble_end);
  const bool none = ao.ensemble_begin == ao.ensemble_end;  // more ranks than ensembles
  ConsoleProgress progress("render: SPBR L=" + std::to_string(repeat_level) + " from " + std::to_string(m.points) +
                           " archived points" +
                           (ranks > 1 ? ", ensembles " + std::to_string(ao.ensemble_begin) + "-" +
                                            std::to_string(ao.ensemble_end - 1) + " on rank 0 of " +
                                            std::to_string(ranks)
                                      : ""));
  render::ArchiveRenderStats stats;
  if (none) {
    image.result.sums = render::Accumulator(image.world_camera.width, image.world_camera.height);
  } else {
    image.result = render::RenderArchive(ao, InFrame(image.world_camera, m.frame), archive, progress.Callback(), &stats);
  }
  progress.Finish();
  if (rank == 0) {
    LogInfo("archive: " + std::to_string(stats.chunks_visible) + " of " + std::to_string(stats.chunks) +
            " chunks in view (" + std::to_string(stats.points_visible) + " points" +
            (o.clip.empty() ? "" : ", " + std::to_string(stats.chunks_clipped) + " cut by the clipping") + "), " +
            std::to_string(stats.passes) + " pass(es)" + (ranks > 1 ? ", " + std::to_string(ranks) + " MPI ranks" : ""));
  }
  image.result.repeat_level = repeat_level;
  image.result.ensembles = drawn;
  image.result.seed = o.image.spbr.seed;
  return image;
}

bool TakeBuildRenderSettings(const render::BuildRecord& record, const GivenImageSettings& given,
                             RenderOptions* options) {
  if (!record.render) return false;
  const ImageSettings& b = *record.render;
  ImageSettings& o = options->image;
  if (!given.repeat_level) o.spbr.repeat_level = b.spbr.repeat_level;
  if (!given.seed) o.spbr.seed = b.spbr.seed;
  if (!given.size) o.width = b.width, o.height = b.height;
  if (!given.background) o.background = b.background;
  if (!given.brightness) o.brightness = b.brightness;
  return true;
}

double WriteRender(const RenderOptions& o, const RenderedImage& image, const RenderOutputs& out) {
  const render::SpbrResult& result = image.result;
  const double gain = render::BrightnessGain(o.image.brightness, result);
  LogInfo("brightness gain " + std::to_string(gain) +
          (o.image.brightness.automatic() ? " (auto)" : ""));
  const ImageF average = render::AverageImage(result, o.image.background, gain);
  std::string inputs;
  for (const std::string& in : out.inputs) inputs += (inputs.empty() ? "" : " ") + in;
  io::PngText text = {{"Software", std::string("candi ") + kVersion},
                      {"candi:seed", std::to_string(result.seed)},
                      {"candi:repeat_level", std::to_string(result.repeat_level)},
                      {"candi:ensembles", std::to_string(result.ensembles)},
                      {"candi:brightness_gain", std::to_string(gain)},
                      {"candi:mode", image.mode},
                      {"candi:inputs", inputs},
                      {"candi:view", render::ViewToJson(image.world_camera)}};
  if (!o.clip.empty()) text["candi:clip"] = o.clip.Describe();
  if (!o.layer_shares.empty()) {
    std::string shares;
    for (const auto& [name, share] : o.layer_shares) {
      shares += (shares.empty() ? "" : " ") + name + "=" + FormatDouble(share);
    }
    text["candi:layer_shares"] = shares;
  }
  Image8 image8 = render::ToImage8(average);
  if (image.legend) {
    const FieldLegend& l = *image.legend;
    text["candi:colour_by"] = l.field + " " + FieldScaleName(l.scale) + " " + FormatDouble(l.lo) + " " +
                              FormatDouble(l.hi) + " outside " + std::to_string(l.outside) + " undefined " +
                              std::to_string(l.undefined);
    if (!render::DrawFieldLegend(l, &image8)) LogWarning("the image is too small for the legend: drawn without it");
  }
  io::WritePng(out.png, image8, text);
  if (!out.png16.empty()) io::WritePng(out.png16, render::ToImage16(average), text);
  if (!out.save_view.empty()) render::SaveView(out.save_view, image.world_camera);
  return gain;
}

}  // namespace candi::pipeline

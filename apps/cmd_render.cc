// candi render IN... -o out.png: SPBR of one or more point files, merged, in memory (a SplatCloud,
// 10 bytes per point copy) or streamed in chunks (frame buffers and a bounded chunk only); or of
// one render archive (candi pack), streamed from its memory-mapped chunks, split over the ranks
// when started by mpirun.
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <map>
#include <memory>
#include <stdexcept>
#include <tuple>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "apps/failure.h"
#include "apps/view_json.h"
#include "apps/view_orientation.h"
#include "core/check.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "core/version.h"
#include "io/image/png_io.h"
#include "io/point_io.h"
#include "render/archive.h"
#include "render/archive_render.h"
#include "render/mpi/mpi_session.h"
#include "render/spbr.h"
#include "render/spbr_stream.h"
#include "render/splat_cloud.h"
#include "sampling/opacity.h"
#include "view/source.h"

namespace candi::app {

namespace {

constexpr uint64_t kStreamThreshold = 50000000;  // points; above, --mode auto streams

void ParseSize(const std::string& text, int* w, int* h) {
  const std::vector<double> v = ParseNumbers(text, 'x', "--size");
  if (v.size() != 2 || v[0] < 1 || v[1] < 1 || v[0] > 16384 || v[1] > 16384 || v[0] != std::floor(v[0]) ||
      v[1] != std::floor(v[1])) {
    throw std::invalid_argument("--size '" + text + "': expected WxH, whole pixels in [1, 16384]");
  }
  *w = static_cast<int>(v[0]);
  *h = static_cast<int>(v[1]);
}

Rgb8 ParseColor(const std::string& text) {
  const std::vector<double> v = ParseNumbers(text, ',', "--background");
  for (double c : v) {
    if (v.size() != 3 || c < 0 || c > 255 || c != std::floor(c)) {
      throw std::invalid_argument("--background '" + text + "': expected r,g,b, each 0..255");
    }
  }
  if (v.size() != 3) throw std::invalid_argument("--background '" + text + "': expected r,g,b");
  return {static_cast<uint8_t>(v[0]), static_cast<uint8_t>(v[1]), static_cast<uint8_t>(v[2])};
}

// -1: automatic; otherwise the gain.
double ParseBrightness(const std::string& text) {
  if (text == "auto") return -1;
  if (text == "none") return 1;
  const std::vector<double> v = ParseNumbers(text, ',', "--brightness");
  if (v.size() != 1 || !(v[0] > 0 && v[0] <= 100)) {
    throw std::invalid_argument("--brightness '" + text + "': expected auto, none or a gain in (0, 100]");
  }
  return v[0];
}

struct Plan {
  ClipRegion clip;  // world coordinates
  int width = 1024, height = 768;
  Rgb8 background;
  double brightness = -1;
  int repeat_level = 100;
  bool stream = false;
};

Plan MakePlan(const RenderArgs& a) {
  Plan p;
  p.clip = ParseClip(a.clip.box, a.clip.planes);
  ParseSize(a.size, &p.width, &p.height);
  p.background = ParseColor(a.background);
  p.brightness = ParseBrightness(a.brightness);
  p.repeat_level = a.opaque ? 1 : a.repeat_level;
  if (a.repeat_level < 1 || a.repeat_level > 100000) {
    throw std::invalid_argument("--repeat-level " + std::to_string(a.repeat_level) + ": must be in [1, 100000]");
  }
  if (!a.alpha.empty() && a.alpha.size() != 1 && a.alpha.size() != a.inputs.size()) {
    throw std::invalid_argument("--alpha: give one value, or one per input (" + std::to_string(a.inputs.size()) + ")");
  }
  for (double alpha : a.alpha) {
    if (!(alpha >= 0 && alpha <= 1)) throw std::invalid_argument("--alpha " + std::to_string(alpha) + ": must be in [0, 1]");
  }
  if (a.opaque && !a.alpha.empty()) throw std::invalid_argument("--opaque and --alpha exclude each other");
  if (a.mode != "auto" && a.mode != "memory" && a.mode != "stream") {
    throw std::invalid_argument("--mode '" + a.mode + "': expected auto, memory or stream");
  }
  if (a.mode == "stream" && !a.alpha.empty()) {
    throw std::invalid_argument("--alpha needs the whole cloud (density): use --mode memory");
  }
  if (!(a.memory_mb > 0)) throw std::invalid_argument("--memory-budget must be > 0 MB");
  return p;
}

// The camera in world coordinates: the view file's, or one that frames the data.
render::Camera WorldCamera(const RenderArgs& a, const Plan& p, const Box3d& world) {
  render::Camera c;
  if (!a.view.empty()) {
    c = LoadView(a.view);
    if (a.size_given) c.width = p.width, c.height = p.height;
    return c;
  }
  return view::FirstView(ClippedBounds(world, p.clip), p.width, p.height, ParseOrientation(a.up, a.from, a.cameras));
}

render::Camera InFrame(render::Camera c, const LocalFrame& frame) {
  c.eye -= frame.origin;
  c.target -= frame.origin;
  return c;
}

// The local density of a point file does not depend on the view: renders of the same file in one
// process (candi build renders each layer from several views) estimate it once. Keyed by the
// file's canonical path, XYZ columns, size and modification time, so a rewritten file is estimated again;
// the density options are the same for every render (AdjustInput sets only threads, which do
// not change the result). Not thread-safe: commands run one at a time.
const sampling::DensityResult& CachedDensity(const std::string& path, const std::string& columns,
                                   const sampling::OpacityOptions& o, const PointCloud& cloud) {
  namespace fs = std::filesystem;
  using Key = std::tuple<std::string, std::string, uintmax_t, fs::file_time_type::rep>;
  static std::map<Key, sampling::DensityResult> cache;
  std::error_code ec;
  const fs::path canonical = fs::canonical(path, ec);
  const uintmax_t size = fs::file_size(path, ec);
  const auto mtime = fs::last_write_time(path, ec).time_since_epoch().count();
  static sampling::DensityResult uncached;
  if (ec) return uncached = sampling::OpacityDensity(o, cloud);
  const Key key{canonical.string(), columns, size, mtime};
  auto it = cache.find(key);
  if (it == cache.end() || it->second.density.size() != cloud.size()) {
    it = cache.insert_or_assign(key, sampling::OpacityDensity(o, cloud)).first;
  }
  return it->second;
}

// Opacity control for input k (ALGORITHMS.md §1): the pixel footprint s is the camera's at its
// target, so the law is met where the view is focused.
void AdjustInput(const RenderArgs& a, const Plan& p, const render::Camera& world_camera, size_t k,
                 PointCloud* cloud) {
  sampling::OpacityOptions o;
  o.alpha = a.alpha.size() == 1 ? a.alpha[0] : a.alpha[k];
  o.repeat_level = p.repeat_level;
  o.image_size = 0;
  o.pixel_size = world_camera.PixelFootprint((world_camera.target - world_camera.eye).norm());
  o.seed = a.seed;
  o.density.threads = a.threads;
  sampling::OpacityResult r = sampling::AdjustOpacity(o, *cloud, CachedDensity(a.inputs[k], a.columns, o, *cloud));
  LogInfo(a.inputs[k] + ": opacity " + FormatDouble(o.alpha) + " at pixel " + FormatDouble(o.pixel_size) +
          " m: " + std::to_string(r.summary.points_in) + " points -> " + std::to_string(r.summary.total_copies) +
          " copies (predicted alpha " + FormatDouble(r.summary.predicted_alpha) + ")");
  if (!r.summary.message.empty()) LogInfo(a.inputs[k] + ": " + r.summary.message);
  *cloud = std::move(r.cloud);
}

render::SpbrResult RenderInMemory(const RenderArgs& a, const Plan& p, render::Camera* world_camera) {
  std::vector<PointCloud> clouds;
  io::PointReadOptions read;
  read.columns = a.columns;
  uint64_t total = 0;
  Box3d world;
  for (const std::string& in : a.inputs) {
    clouds.push_back(io::ReadPointCloud(in, read));
    total += clouds.back().size();
    if (!clouds.back().empty()) world.Extend(clouds.back().WorldBounds());
  }
  if (total == 0) throw InputError("nothing to render: the inputs hold no points");
  *world_camera = WorldCamera(a, p, world);
  // Opacity control sees the whole cloud (its density does not depend on the clipping); the
  // clipping then removes points, as the archive renderer skips them.
  for (size_t k = 0; k < clouds.size() && !a.alpha.empty(); ++k) AdjustInput(a, p, *world_camera, k, &clouds[k]);
  for (PointCloud& c : clouds) ClipCloud(p.clip, &c);
  std::vector<const PointCloud*> pointers;
  for (const PointCloud& c : clouds) pointers.push_back(&c);
  render::SplatCloudOptions build;
  build.repeat_level = p.repeat_level;
  build.seed = a.seed;
  build.use_multiplicity = !a.opaque;
  ConsoleProgress building("render: preparing " + std::to_string(total) + " points");
  const render::SplatCloud splats = render::BuildSplatCloud(build, pointers, building.Callback());
  building.Finish();
  clouds.clear();
  if (splats.copies() == 0) LogInfo("every point was removed (alpha 0): the image shows the background");
  render::SpbrOptions options;
  options.point_size = a.point_size;
  options.ensembles = a.preview;
  options.threads = a.threads;
  ConsoleProgressOptions po;
  po.unit = "ensembles";
  ConsoleProgress progress("render: SPBR L=" + std::to_string(p.repeat_level), po);
  render::SpbrResult result = render::RenderSpbr(options, InFrame(*world_camera, splats.frame), splats, progress.Callback());
  progress.Finish();
  return result;
}

// Bounds from the headers when every input states them, else from a pass over the points.
Box3d StreamBounds(const RenderArgs& a, const io::PointReadOptions& read, uint64_t* total) {
  Box3d world;
  bool all_headers = true;
  *total = 0;
  for (const std::string& in : a.inputs) {
    auto r = io::OpenPointReader(in, read);
    if (r->info().header_bounds) world.Extend(*r->info().header_bounds); else all_headers = false;
    if (r->info().count != io::kUnknownCount) *total += r->info().count;
  }
  if (all_headers) return world;
  world = Box3d();
  *total = 0;
  ConsoleProgress progress("render: bounds");
  PointCloud chunk;
  for (const std::string& in : a.inputs) {
    auto r = io::OpenPointReader(in, read);
    while (r->Read(1 << 20, &chunk) > 0) {
      world.Extend(chunk.WorldBounds());
      *total += chunk.size();
      progress.Update(*total, 0);
    }
  }
  return world;
}

render::SpbrResult RenderStreaming(const RenderArgs& a, const Plan& p, render::Camera* world_camera) {
  io::PointReadOptions read;
  read.columns = a.columns;
  read.scalar_fields = false;  // geometry and colour; multiplicities need --mode memory
  uint64_t total = 0;
  const Box3d world = StreamBounds(a, read, &total);
  if (total == 0 || world.IsEmpty()) throw InputError("nothing to render: the inputs hold no points");
  const LocalFrame frame = render::RenderFrameFor(world);
  *world_camera = WorldCamera(a, p, world);
  if (world_camera->projection != render::Projection::kPerspective) {
    throw std::invalid_argument("--mode stream draws perspective views; use --mode memory for orthographic views");
  }
  render::SpbrStreamOptions o;
  o.repeat_level = p.repeat_level;
  o.seed = a.seed;
  o.point_size = a.point_size;
  o.threads = a.threads;
  o.memory_budget = static_cast<uint64_t>(a.memory_mb * 1048576.0);
  render::SpbrStreamRenderer renderer(o, InFrame(*world_camera, frame), frame);
  ConsoleProgress progress("render: SPBR L=" + std::to_string(p.repeat_level) + " streaming, " +
                           std::to_string(renderer.passes()) + " pass(es)");
  uint64_t done = 0;
  PointCloud chunk;
  for (int pass = 0; pass < renderer.passes(); ++pass) {
    renderer.BeginPass(pass);
    for (const std::string& in : a.inputs) {
      auto r = io::OpenPointReader(in, read);
      while (r->Read(1 << 20, &chunk) > 0) {
        done += chunk.size();
        ClipCloud(p.clip, &chunk);
        renderer.Add(chunk);
        progress.Update(done, total * renderer.passes());
      }
    }
    renderer.EndPass();
  }
  progress.Finish();
  return renderer.Finish();
}

void WriteOutputs(const RenderArgs& a, const Plan& p, const render::SpbrResult& result,
                  const render::Camera& world_camera, const char* mode) {
  const double gain = p.brightness < 0 ? (result.ensembles > 1 ? render::AutoBrightnessGain(result) : 1.0)
                                       : p.brightness;
  LogInfo("brightness gain " + std::to_string(gain) + (p.brightness < 0 ? " (auto)" : ""));
  const ImageF average = render::AverageImage(result, p.background, gain);
  std::string inputs;
  for (const std::string& in : a.inputs) inputs += (inputs.empty() ? "" : " ") + in;
  io::PngText text = {{"Software", std::string("candi ") + kVersion},
                        {"candi:seed", std::to_string(result.seed)},
                        {"candi:repeat_level", std::to_string(result.repeat_level)},
                        {"candi:ensembles", std::to_string(result.ensembles)},
                        {"candi:brightness_gain", std::to_string(gain)},
                        {"candi:mode", mode},
                        {"candi:inputs", inputs},
                        {"candi:view", ViewToJson(world_camera)}};
  if (!p.clip.empty()) text["candi:clip"] = p.clip.Describe();
  io::WritePng(a.output, render::ToImage8(average), text);
  if (!a.output16.empty()) io::WritePng(a.output16, render::ToImage16(average), text);
  if (!a.save_view.empty()) SaveView(a.save_view, world_camera);
  std::printf("%s: %dx%d, SPBR L=%d (%d ensembles), %llu point copies, %.0f ms, gain %.2f, seed %llu\n",
              a.output.c_str(), world_camera.width, world_camera.height, result.repeat_level,
              result.ensembles, static_cast<unsigned long long>(result.copies), result.milliseconds,
              gain, static_cast<unsigned long long>(result.seed));
}

// One archive, streamed; this rank's share of the ensembles (all of them for one process).
render::SpbrResult RenderArchiveInput(const RenderArgs& a, const Plan& p, render::Camera* world_camera, int rank,
                                      int ranks) {
  if (!a.alpha.empty()) {
    throw std::invalid_argument("--alpha needs point files: an archive holds one copy per point");
  }
  if (!(a.chunk_budget_mb > 0)) throw std::invalid_argument("--chunk-budget must be > 0 MB");
  const render::Archive archive(a.inputs[0]);
  const render::ArchiveManifest& m = archive.manifest();
  *world_camera = WorldCamera(a, p, m.bounds.Translated(m.frame.origin));
  const int drawn = a.preview > 0 ? std::min(a.preview, p.repeat_level) : p.repeat_level;
  render::ArchiveRenderOptions o;
  o.repeat_level = p.repeat_level;
  o.seed = a.seed;
  o.point_size = a.point_size;
  o.threads = a.threads;
  o.memory_budget = static_cast<uint64_t>(a.memory_mb * 1048576.0);
  o.chunk_budget = static_cast<uint64_t>(a.chunk_budget_mb * 1048576.0);
  o.clip = p.clip.ToLocal(m.frame.origin);
  render::mpi::EnsembleShare(drawn, rank, ranks, &o.ensemble_begin, &o.ensemble_end);
  const bool none = o.ensemble_begin == o.ensemble_end;  // more ranks than ensembles
  ConsoleProgress progress("render: SPBR L=" + std::to_string(p.repeat_level) + " from " +
                           std::to_string(m.points) + " archived points" +
                           (ranks > 1 ? ", ensembles " + std::to_string(o.ensemble_begin) + "-" +
                                            std::to_string(o.ensemble_end - 1) + " on rank 0 of " +
                                            std::to_string(ranks)
                                      : ""));
  render::ArchiveRenderStats stats;
  render::SpbrResult result;
  if (none) {
    result.sums = render::Accumulator(world_camera->width, world_camera->height);
  } else {
    result = render::RenderArchive(o, InFrame(*world_camera, m.frame), archive, progress.Callback(), &stats);
  }
  progress.Finish();
  if (rank == 0) {
    LogInfo("archive: " + std::to_string(stats.chunks_visible) + " of " + std::to_string(stats.chunks) +
            " chunks in view (" + std::to_string(stats.points_visible) + " points" +
            (p.clip.empty() ? "" : ", " + std::to_string(stats.chunks_clipped) + " cut by the clipping") + "), " +
            std::to_string(stats.passes) +
            " pass(es)" + (ranks > 1 ? ", " + std::to_string(ranks) + " MPI ranks" : ""));
  }
  result.repeat_level = p.repeat_level;
  result.ensembles = drawn;
  result.seed = a.seed;
  return result;
}

// Renders an archive, under mpirun as one of the ranks: every rank draws its ensembles, the
// ranks agree that all succeeded, the sums are added on rank 0, which alone writes the image
// (atomically). A failed rank makes every rank fail: no image.
int RunRenderArchive(const RenderArgs& args, const Plan& plan) {
  std::unique_ptr<render::mpi::Session> session;
  if (render::mpi::LaunchedByMpi()) session = std::make_unique<render::mpi::Session>();
  const int rank = session ? session->rank() : 0, ranks = session ? session->size() : 1;
  if (rank != 0) SetConsoleProgressEnabled(false);
  render::Camera world_camera;
  render::SpbrResult result;
  std::exception_ptr failure;
  try {
    result = RenderArchiveInput(args, plan, &world_camera, rank, ranks);
  } catch (...) {
    failure = std::current_exception();
  }
  if (!session) {
    if (failure) std::rethrow_exception(failure);
  } else {
    // Every rank learns every failure; rank 0 prints them all before any process exits, since
    // mpirun ends the job when the first process exits non-zero and a report that another rank
    // had yet to print would be lost. The barrier holds every rank until it is printed.
    const FailureReport mine = failure ? DescribeFailure(failure) : FailureReport{};
    const auto failures = session->GatherFailures(mine.exit_code, mine.text);
    if (!failures.empty()) {
      if (rank == 0) {
        for (const auto& f : failures) {
          const size_t skip = f.message.rfind("candi: ", 0) == 0 ? 7 : 0;  // the report's own prefix
          std::fprintf(stderr, "candi: MPI rank %d of %d failed: %s\n", f.rank, ranks, f.message.c_str() + skip);
        }
        std::fprintf(stderr, "candi: every rank stopped because %s failed; no image written\n",
                     failures.size() == 1 && failures[0].rank != 0 ? "another rank" : "a rank");
        std::fflush(stderr);
      }
      session->Barrier();
      throw ReportedFailure(failures.front().exit_code);
    }
    session->ReduceToRoot(&result);
    if (rank != 0) return kOk;
  }
  WriteOutputs(args, plan, result, world_camera, ranks > 1 ? "archive, MPI" : "archive");
  return kOk;
}

}  // namespace

int RunRender(const RenderArgs& args) {
  const Plan plan = MakePlan(args);
  for (const std::string& in : args.inputs) {
    if (!render::IsArchive(in)) continue;
    if (args.inputs.size() > 1) throw std::invalid_argument(in + " is an archive: render it alone");
    return RunRenderArchive(args, plan);
  }
  if (render::mpi::LaunchedByMpi()) {
    throw std::invalid_argument("under mpirun, candi render splits an archive (candi pack) over the ranks; "
                                "point files render in one process");
  }
  bool stream = args.mode == "stream";
  if (args.mode == "auto" && args.alpha.empty()) {
    uint64_t stated = 0;
    for (const std::string& in : args.inputs) {
      io::PointReadOptions read;
      read.columns = args.columns;
      const uint64_t count = io::OpenPointReader(in, read)->info().count;
      if (count != io::kUnknownCount) stated += count;
    }
    stream = stated > kStreamThreshold;
  }
  render::Camera world_camera;
  const render::SpbrResult result = stream ? RenderStreaming(args, plan, &world_camera)
                                           : RenderInMemory(args, plan, &world_camera);
  WriteOutputs(args, plan, result, world_camera, stream ? "stream" : "memory");
  return kOk;
}

}  // namespace candi::app

// candi render, view, publish, section: see-through images of point files or an archive
// (pipeline/render.h; an archive's ensembles split over the ranks under mpirun), the browser viewer
// (view/), the static web site (view/publish.h) and sections (pipeline/section.h). candi opacity
// is in opacity_command.cc.
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "apps/failure.h"
#include "core/atomic_file.h"
#include "core/field_colour.h"
#include "core/check.h"
#include "core/interrupt.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "io/point_io.h"
#include "pipeline/render.h"
#include "pipeline/section.h"
#include "render/archive.h"
#include "render/build_record.h"
#include "render/mpi/archive_ranks.h"
#include "render/mpi/mpi_session.h"
#include "render/view_json.h"
#include "view/publish.h"
#include "view/server.h"
#include "view/source.h"

namespace candi::apps {

namespace {

namespace fs = std::filesystem;

// --clip-box and --clip-plane of render, view and section.
struct ClipArgs {
  std::string box;
  std::vector<std::string> planes;
};

void AddClip(Command& c, ClipArgs& clip) {
  c.Option("--clip-box", clip.box, "Keep only points inside this box, world (survey) coordinates: "
           "xmin,ymin,zmin,xmax,ymax,zmax");
  c.Option("--clip-plane", clip.planes, "Keep only the side of a plane its normal points into: px,py,pz,nx,ny,nz "
           "(world coordinates; repeat for several)").Repeatable();
}

}  // namespace

void AddFieldColouring(Command& c, FieldArgs& f) {
  c.Option("--colour-by", f.field, "Colour the points by a scalar field (e.g. distance from candi compare, "
           "intensity, classification; elevation: world z), with a legend of the scale");
  c.Option("--field-range", f.range, "With --colour-by: the range lo,hi of the scale; values outside are grey "
           "(default: from the values' 2nd-98th percentiles, symmetric about 0 on a diverging scale)");
  c.Option("--field-scale", f.scale, "With --colour-by: auto, diverging (signed, e.g. deviations), sequential or "
           "classes (LAS classes)");
}

FieldColouring ParseFieldColouring(const FieldArgs& f) {
  FieldColouring c;
  if (f.field.empty()) {
    if (!f.range.empty() || f.scale != "auto") throw std::invalid_argument("--field-range and --field-scale need --colour-by");
    return c;
  }
  c.field = f.field;
  c.scale = ParseFieldScale(f.scale);
  if (!f.range.empty()) {
    const std::vector<double> v = ParseNumbers(f.range, ',', "--field-range");
    if (v.size() != 2) throw std::invalid_argument("--field-range '" + f.range + "': expected lo,hi");
    c.lo = v[0];
    c.hi = v[1];
  }
  c.Check();
  return c;
}

namespace {

// --up, --from and --cameras: the default view's orientation.
struct OrientationArgs {
  std::string up, from, cameras;
};

render::Orientation ParseOrientation(const OrientationArgs& a) {
  render::Orientation o = a.cameras.empty() ? render::Orientation() : pipeline::OrientationOfCameras(a.cameras);
  if (!a.up.empty()) o.up = ParseDirection(a.up, "--up");
  if (!a.from.empty()) o.view_dir = ParseDirection(a.from, "--from");
  return o;
}

render::mpi::FailureDescriber Describer() {
  return [](std::exception_ptr failure) {
    const FailureReport report = DescribeFailure(failure);
    return std::pair<int, std::string>{report.exit_code, report.text};
  };
}

// -------------------------------------------------------------------------------------- render

struct RenderArgs {
  std::vector<std::string> inputs;
  pipeline::RenderOutputs outputs;     // png (8-bit), png16, save_view
  pipeline::RenderOptions options;
  std::string size = "1024x768";       // WxH (overrides a view's size when given explicitly)
  std::string view;                    // a view file (world coordinates)
  std::string background = "0,0,0";    // r,g,b
  std::string brightness = "auto";     // auto | none | a gain
  std::string mode = "auto";           // auto | memory | stream
  double memory_mb = 2048;             // stream mode and archives: z-buffers resident per pass
  double chunk_budget_mb = 256;        // archive input: chunks mapped at once (8 bytes a point)
  OrientationArgs orientation;
  ClipArgs clip;
  FieldArgs field;
  pipeline::GivenImageSettings given;  // the rest comes from a build's record
};

Brightness ParseBrightness(const std::string& text) {
  try {
    return Brightness::Parse(text);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("--brightness ") + e.what());
  }
}

pipeline::RenderOptions RenderOptionsOf(const RenderArgs& a) {
  pipeline::RenderOptions o = a.options;
  o.clip = ParseClip(a.clip.box, a.clip.planes);
  ParseSize(a.size, "--size", &o.image.width, &o.image.height);
  o.image.background = ParseColour(a.background, "--background");
  o.image.brightness = ParseBrightness(a.brightness);
  o.colour_by = ParseFieldColouring(a.field);
  if (!o.alpha.empty() && o.alpha.size() != 1 && o.alpha.size() != a.inputs.size()) {
    throw std::invalid_argument("--alpha: give one value, or one per input (" + std::to_string(a.inputs.size()) + ")");
  }
  if (a.mode != "auto" && a.mode != "memory" && a.mode != "stream") {
    throw std::invalid_argument("--mode '" + a.mode + "': expected auto, memory or stream");
  }
  o.mode = a.mode == "memory" ? pipeline::RenderMode::kMemory
           : a.mode == "stream" ? pipeline::RenderMode::kStream : pipeline::RenderMode::kAuto;
  if (!(a.memory_mb > 0)) throw std::invalid_argument("--memory-budget must be > 0 MB");
  o.memory_budget = static_cast<uint64_t>(a.memory_mb * 1048576.0);
  o.Check();
  if (!a.view.empty()) {
    // A page's saved or shared view also carries the layers' shares and the clipping.
    render::SavedViewSettings saved;
    o.view = render::LoadView(a.view, &saved);
    for (size_t i = 0; i < saved.layer_names.size(); ++i) {
      o.layer_shares.push_back({saved.layer_names[i], saved.layer_shares[i]});
    }
    o.clip = o.clip.And(saved.clip);
  } else {
    o.orientation = ParseOrientation(a.orientation);
  }
  return o;
}

void PrintRender(const std::string& output, const pipeline::RenderedImage& image, double gain) {
  const render::SpbrResult& r = image.result;
  std::printf("%s: %dx%d, SPBR L=%d (%d ensembles), %llu point copies, %.0f ms, gain %.2f, seed %llu\n",
              output.c_str(), image.world_camera.width, image.world_camera.height, r.repeat_level, r.ensembles,
              static_cast<unsigned long long>(r.copies), r.milliseconds, gain, static_cast<unsigned long long>(r.seed));
}

// Renders an archive, under mpirun as one of the ranks: every rank draws its ensembles, the
// ranks agree that all succeeded, the sums are added on rank 0, which alone writes the image
// (atomically). A failed rank makes every rank fail: no image.
int RenderArchive(const RenderArgs& a, pipeline::RenderOptions o) {
  if (!o.alpha.empty()) throw std::invalid_argument("--alpha needs point files: an archive holds one copy per point");
  if (!(a.chunk_budget_mb > 0)) throw std::invalid_argument("--chunk-budget must be > 0 MB");
  o.chunk_budget = static_cast<uint64_t>(a.chunk_budget_mb * 1048576.0);
  std::unique_ptr<render::mpi::Session> session;
  if (render::mpi::LaunchedByMpi()) session = std::make_unique<render::mpi::Session>();
  const int rank = session ? session->rank() : 0, ranks = session ? session->size() : 1;
  if (rank != 0) SetConsoleProgressEnabled(false);
  pipeline::RenderedImage image;
  std::exception_ptr failure;
  try {
    const render::Archive archive(a.inputs[0]);
    image = pipeline::RenderArchiveEnsembles(o, archive, rank, ranks);
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
    session->ReduceToRoot(&image.result);
    if (rank != 0) return kOk;
  }
  pipeline::RenderOutputs outputs = a.outputs;
  outputs.inputs = a.inputs;
  PrintRender(outputs.png, image, pipeline::WriteRender(o, image, outputs));
  return kOk;
}

int RunRender(const RenderArgs& a) {
  pipeline::RenderOptions o = RenderOptionsOf(a);
  for (const std::string& in : a.inputs) {
    // An archive, a build directory or a demo's output: what a page (candi view, a site) shows;
    // a build draws with its own settings where no flag says otherwise.
    const std::string archive = render::FindArchive(in);
    if (archive.empty()) continue;
    if (a.inputs.size() > 1) throw std::invalid_argument(in + " is an archive: render it alone");
    const std::string build = render::FindBuild(in);
    if (!build.empty() && pipeline::TakeBuildRenderSettings(render::ReadBuildRecord(build), a.given, &o)) {
      const ImageSettings& s = o.image;
      LogInfo("the build's render settings: L=" + std::to_string(s.spbr.repeat_level) + ", seed " +
              std::to_string(s.spbr.seed) + ", " + std::to_string(s.width) + "x" + std::to_string(s.height) +
              ", background " + std::to_string(s.background.r) + "," + std::to_string(s.background.g) + "," +
              std::to_string(s.background.b) + ", brightness " + s.brightness.ToString());
      o.Check();
    }
    RenderArgs one = a;
    one.inputs = {archive};
    return RenderArchive(one, o);
  }
  if (render::mpi::LaunchedByMpi()) {
    throw std::invalid_argument("under mpirun, candi render splits an archive (candi pack) over the ranks; "
                                "point files render in one process");
  }
  const pipeline::RenderedImage image = pipeline::RenderPointFiles(o, a.inputs);
  pipeline::RenderOutputs outputs = a.outputs;
  outputs.inputs = a.inputs;
  PrintRender(outputs.png, image, pipeline::WriteRender(o, image, outputs));
  return kOk;
}

void AddRender(Command& root) {
  RenderArgs& a = root.Keep<RenderArgs>();
  pipeline::RenderOptions& o = a.options;
  Command c = root.Add("render", "Render point files see-through with SPBR (stochastic point-based rendering), "
                                 "merged into one image");
  c.Option("inputs", a.inputs, "Point files " CANDI_POINT_FILES_READ ", or one archive (candi pack, a build directory "
           "or a demo's output); under mpirun the ranks share the ensembles").Required();
  c.Option("-o,--output", a.outputs.png, "Output PNG (8-bit)").Required();
  c.Option("--png16", a.outputs.png16, "Also write a 16-bit PNG (for analysis)");
  pipeline::GivenImageSettings& given = a.given;
  c.Option("-L,--repeat-level", o.image.spbr.repeat_level, "Ensembles averaged (more: less noise, slower)")
      .OnGiven([&given] { given.repeat_level = true; });
  c.Option("--seed", o.image.spbr.seed, "Seed of the ensemble assignment").OnGiven([&given] { given.seed = true; });
  c.Option("--size", a.size, "Image size WxH").OnGiven([&o, &given] { o.size_given = given.size = true; });
  c.Option("--view", a.view, "View JSON (world coordinates) to render from; a page's saved view also sets the "
           "layers' shares and the clipping");
  c.Option("--save-view", a.outputs.save_view, "Write the view used as JSON (to repeat the render)");
  c.Option("--background", a.background, "Background colour r,g,b").OnGiven([&given] { given.background = true; });
  c.Option("--brightness", a.brightness, "auto, none, or a gain (transparent images get dark)")
      .OnGiven([&given] { given.brightness = true; });
  c.Option("--alpha", o.alpha, "Target opacity per input (one value for all, or one each)").Delimiter(',');
  c.Flag("--opaque", o.image.spbr.opaque, "Opaque rendering (L = 1, one point per pixel)");
  c.Option("--threads", o.threads, "Threads (0: all)").Range(0, 256);
  c.Option("--point-size", o.image.spbr.point_size, "Point size in pixels (>= 1; stochastic rounding)");
  c.Option("--preview", o.preview, "Render only the first k ensembles (progressive preview)");
  c.Option("--mode", a.mode, "auto, memory (fast, 10 B/point) or stream (bounded memory)");
  c.Option("--memory-budget", a.memory_mb, "Stream mode and archives: MB of z-buffers resident per pass (12 B per "
           "pixel and ensemble)");
  c.Option("--chunk-budget", a.chunk_budget_mb, "Archive input: MB of chunks mapped at once (8 B a point)");
  c.Option("--columns", o.columns, "XYZ/PTS column spec");
  c.Option("--up", a.orientation.up, "Without --view: world up, x,y,z (default 0,0,1; COLMAP's frame: 0,-1,0)");
  c.Option("--from", a.orientation.from, "Without --view: the direction the view looks in, x,y,z (default: oblique, "
           "from above)");
  c.Option("--cameras", a.orientation.cameras, "Without --view: a COLMAP model (e.g. WORK/sparse/0) whose frame the "
           "points are in: up and the viewing side from its cameras");
  AddClip(c, a.clip);
  AddFieldColouring(c, a.field);
  c.Run([&a] { return RunRender(a); });
  c.Footer("Example: candi render building.ply foundation.ply -o site.png -L 100 --alpha 0.3,0.8");
}

// ---------------------------------------------------------------------------------------- view

struct ViewArgs {
  std::vector<std::string> inputs;  // a build directory, an archive, or point files
  view::ServerOptions server;       // host, threads
  int port = 8765;                  // 0: any free port; the default: the next free one from it
  OrientationArgs orientation;
  std::string columns;              // XYZ/PTS inputs
  ClipArgs clip;                    // the clipping the page starts with
  FieldArgs field;                  // point files: coloured by a field
  uint64_t preview = 10000000;      // point files of more points: a preview of this many first
};

// The source to show: a build directory or an archive opened, or point files packed into a
// temporary archive (removed on exit, and by an interrupt).
struct OpenedSource {
  view::ViewerSource source;
  ~OpenedSource() {
    if (source.temporary_dir.empty()) return;
    std::error_code ignored;
    fs::remove_all(source.temporary_dir, ignored);
    UnregisterTempPath(source.temporary_id);  // registered by the packing (removed on Ctrl-C)
  }
};

// Opens the source; for point files of more than twice `a.preview` points whose points are
// records (and no colouring by a field, `allow_preview`), a preview's archive, and returns true:
// the caller then packs every point (PackWhole) while the preview is served.
bool OpenSource(const ViewArgs& a, const render::Orientation& orientation, bool allow_preview, OpenedSource* opened) {
  std::error_code ec;
  const FieldColouring colour_by = ParseFieldColouring(a.field);
  if (a.inputs.size() == 1 && fs::is_directory(a.inputs[0], ec)) {
    if (colour_by.active()) {
      throw std::invalid_argument("--colour-by needs point files: " + a.inputs[0] +
                                  " is an archive or a build, which holds the points' colours, not their fields");
    }
    opened->source = view::OpenViewerSource(a.inputs[0], orientation);
    return false;
  }
  for (const std::string& in : a.inputs) {
    if (fs::is_directory(in, ec)) throw std::invalid_argument(in + " is a directory: open it alone");
  }
  if (allow_preview && a.preview > 0 && !colour_by.active() && view::PreviewEvery(a.inputs, a.columns, a.preview) > 0) {
    ConsoleProgress progress("view: packing a preview of " + std::to_string(a.preview) + " points");
    std::optional<view::ViewerSource> preview =
        view::PackPreviewSource(a.inputs, a.columns, orientation, a.preview, progress.Callback());
    progress.Finish();
    CANDI_CHECK(preview.has_value()) << "PreviewEvery promised a preview";
    opened->source = std::move(*preview);
    return true;
  }
  ConsoleProgress progress("view: packing " + std::to_string(a.inputs.size()) + " point file(s)");
  opened->source = view::PackViewerSource(a.inputs, a.columns, orientation, progress.Callback(), colour_by);
  progress.Finish();
  return false;
}

// What the viewer draws from now (sections read it on their own thread): the preview's archive,
// then the whole one.
struct Current {
  std::mutex mutex;
  const view::ViewerSource* source = nullptr;
  const render::Archive* archive = nullptr;
  std::pair<const view::ViewerSource*, const render::Archive*> Get() {
    std::lock_guard<std::mutex> lock(mutex);
    return {source, archive};
  }
  void Set(const view::ViewerSource* s, const render::Archive* a) {
    std::lock_guard<std::mutex> lock(mutex);
    source = s, archive = a;
  }
};

// Behind a preview: every point packed, on a thread of its own, then served instead of the
// preview; a failure stops the server and is rethrown by Finish().
class PackWhole {
 public:
  PackWhole(const ViewArgs& a, const render::Orientation& orientation, const ClipRegion& clip, uint64_t points,
            view::Server* server, Current* current)
      : thread_([=, &a] {
          try {
            ConsoleProgress progress("view: packing all " + std::to_string(points) + " points");
            whole_.source = view::PackViewerSource(a.inputs, a.columns, orientation, progress.Callback());
            progress.Finish();
            whole_.source.settings.clip = clip;
            archive_ = std::make_unique<render::Archive>(whole_.source.archive_dir);
            current->Set(&whole_.source, archive_.get());
            server->Replace(whole_.source, *archive_, view::LocalRangeRenderer(*archive_));
            LogInfo("view: all " + std::to_string(archive_->manifest().points) + " points packed: the pages show them");
          } catch (...) {
            error_ = std::current_exception();
            server->Stop();
          }
        }) {}
  ~PackWhole() { Join(); }
  void Join() {
    if (thread_.joinable()) thread_.join();
  }
  // Waits for the packing; rethrows its error.
  void Finish() {
    Join();
    if (error_) std::rethrow_exception(error_);
  }

 private:
  OpenedSource whole_;
  std::unique_ptr<render::Archive> archive_;
  std::exception_ptr error_;
  std::thread thread_;  // last: starts once the members above exist
};

int RunView(const ViewArgs& a) {
  a.server.Check();  // before the source is opened (or packed)
  std::unique_ptr<render::mpi::Session> session;
  if (render::mpi::LaunchedByMpi()) session = std::make_unique<render::mpi::Session>(/*serialized=*/true);
  if (session && session->rank() != 0) {
    render::mpi::ServeArchiveRequests(*session, a.server.threads, Describer());
    return kOk;
  }
  OpenedSource opened;
  const render::Orientation orientation = ParseOrientation(a.orientation);
  const bool previewed = OpenSource(a, orientation, /*allow_preview=*/!session, &opened);
  view::ViewerSource& source = opened.source;
  source.settings.clip = ParseClip(a.clip.box, a.clip.planes);
  const render::Archive archive(source.archive_dir);
  Current current;
  current.Set(&source, &archive);
  view::RangeRenderer renderer = view::LocalRangeRenderer(archive);
  std::string stop = render::mpi::kStopRequest;
  struct StopRanks {  // however rank 0 leaves, the other ranks stop serving
    render::mpi::Session* session;
    std::string* stop;
    ~StopRanks() {
      if (session) session->Broadcast(stop);
    }
  } stop_ranks{nullptr, &stop};
  if (session) {
    std::string dir = fs::absolute(source.archive_dir).string();
    session->Broadcast(&dir);
    stop_ranks.session = session.get();
    renderer = [&session, &archive, threads = a.server.threads](const render::ArchiveRenderOptions& o,
                                                                 const render::Camera& camera,
                                                                 const std::function<bool()>&) {
      std::string request = render::mpi::EncodeArchiveRequest(o, camera);
      session->Broadcast(&request);
      return render::mpi::RenderRequestShare(*session, archive, request, threads, Describer());
    };
    LogInfo("view: " + std::to_string(session->size()) + " MPI ranks share every image's ensembles (the archive must "
            "be at the same path on every rank's machine)");
  }
  view::ServerOptions options = a.server;
  options.log = [](const std::string& line) { LogInfo(line); };
  options.section = [&current, threads = a.server.threads](uint64_t seq, const view::SectionRequest& r,
                                                             const view::ViewState& state,
                                                             const view::SectionControl& control) {
    pipeline::SectionOptions o;
    o.threads = threads;
    o.max_points = control.max_points;
    o.checkpoint = control.checkpoint;
    const auto [drawn, drawn_archive] = current.Get();
    return pipeline::ExportViewerSection(drawn->archive_dir, drawn_archive->manifest(), o, seq, r, state);
  };
  if (a.server.host != "127.0.0.1" && a.server.host != "localhost" && a.server.host != "::1") {
    LogWarning("serving on " + a.server.host + ": anyone who can reach this machine and has the address with its "
               "token sees the data; the connection is not encrypted");
  }
  // The default port, or the next free one (as Jupyter does); an explicit port or 0 as given.
  // Declared before the server: the whole archive, once served, must outlive it.
  std::optional<PackWhole> whole;
  std::unique_ptr<view::Server> server;
  const int tries = a.port == 8765 ? 20 : 1;
  for (int i = 0; i < tries && !server; ++i) {
    options.port = a.port == 0 ? 0 : a.port + i;
    try {
      server = std::make_unique<view::Server>(options, source, archive, renderer);
    } catch (const std::runtime_error& e) {
      if (i + 1 == tries) throw InputError(e.what());
    }
  }
  LogInfo("view: " + source.title + " (" + source.kind + ", " + std::to_string(archive.manifest().points) +
          " points in " + std::to_string(archive.manifest().chunks.size()) + " chunks" +
          (previewed ? ": a preview, one point in " + std::to_string(source.preview_every) + " of " +
                           std::to_string(source.preview_points) + ", until all are packed"
                     : "") +
          "); Ctrl-C stops");
  std::printf("candi view: %s\n", server->Url().c_str());
  std::fflush(stdout);
  if (previewed) whole.emplace(a, orientation, source.settings.clip, source.preview_points, server.get(), &current);
  try {
    server->Run();
  } catch (...) {
    if (whole) whole->Join();  // before the server goes
    throw;
  }
  if (whole) whole->Finish();  // a failure to pack every point: its error
  return kOk;
}

void AddView(Command& root) {
  ViewArgs& a = root.Keep<ViewArgs>();
  Command c = root.Add("view", "Open an archive in the browser: orbit it see-through while the server renders "
                               "(SPBR), the image refining as you watch");
  c.Option("inputs", a.inputs, "A build directory (candi build), a render archive (candi pack), or point files "
           "(packed on the fly into a temporary archive)").Required();
  c.Option("--host", a.server.host, "Address to serve on (default 127.0.0.1; 0.0.0.0 serves your network: anyone "
           "with the printed address and token sees the data)");
  c.Option("--port", a.port, "Port (0: any free one)").Range(0, 65535);
  c.Option("--up", a.orientation.up, "World up for the first view, x,y,z (default 0,0,1; COLMAP's frame: 0,-1,0)");
  c.Option("--from", a.orientation.from, "Direction the first view looks in, x,y,z (default: oblique, from above)");
  c.Option("--cameras", a.orientation.cameras, "A COLMAP model (e.g. WORK/sparse/0) whose frame the points are in: "
           "the first view's up and side from its cameras");
  c.Option("--columns", a.columns, "XYZ/PTS column spec");
  c.Option("--threads", a.server.threads, "Render threads (0: all)").Range(0, 256);
  c.Option("--max-pages", a.server.max_clients, "Pages open at once (default 16)");
  c.Option("--max-pixels", a.server.max_pixels, "Image pixels of all open pages together (16 bytes each; default "
           "33554432: 16 full-HD pages or two of 4096x4096)");
  c.Option("--section-seconds", a.server.section_seconds, "A section export's time limit, s (default 120)");
  c.Option("--section-max-points", a.server.section_max_points, "The most points an exported slab may hold "
           "(default 20000000)");
  c.Option("--preview", a.preview, "Point files of more than twice this many points (binary PLY, LAS): a preview of "
           "this many is shown first, the whole replacing it once packed (0: none; default 10000000)");
  AddClip(c, a.clip);
  AddFieldColouring(c, a.field);
  c.Run([&a] { return RunView(a); });
  c.Footer("Example: candi view borobudur_out/   (then open the printed http://127.0.0.1:8765/?token=... address)");
}

// ------------------------------------------------------------------------------------- publish

struct PublishArgs {
  std::string input;                // a build directory, a demo's output, or an archive
  std::string output;               // the site's folder
  view::PublishOptions options;
  OrientationArgs orientation;
};

int RunPublish(const PublishArgs& a) {
  a.options.Check();
  ConsoleProgress progress("publish");
  const view::PublishStats s = view::PublishSite(a.options, a.input, a.output, ParseOrientation(a.orientation),
                                                 progress.Callback());
  progress.Finish();
  const double mb = 1e-6;
  std::printf("%s: %llu points in %llu chunks, %llu groups x %d pages = %llu files\n", a.output.c_str(),
              static_cast<unsigned long long>(s.points), static_cast<unsigned long long>(s.chunks),
              static_cast<unsigned long long>(s.groups), s.repeat_level, static_cast<unsigned long long>(s.files));
  std::printf("  data %.1f MB: %.2f bytes a point (the archive: 8; COPC: ~5)\n", s.data_bytes * mb, s.BytesPerPoint());
  std::printf("  before the first image: %.2f MB (the page, site.json and every group's first page)\n",
              s.first_image_bytes * mb);
  std::printf("  site %.1f MB, written in %.2f s (%.1f M points/s)\n", s.site_bytes * mb, s.seconds,
              s.seconds > 0 ? s.points / s.seconds * 1e-6 : 0.0);
  std::printf("  serve it with any static web server, e.g.: python3 -m http.server -d %s 8000\n", a.output.c_str());
  return kOk;
}

void AddPublish(Command& root) {
  PublishArgs& a = root.Keep<PublishArgs>();
  view::PublishOptions& o = a.options;
  Command c = root.Add("publish", "Write the archive as a static web site that renders it see-through (SPBR) in "
                                  "the visitor's browser with WebGL2: no server-side code, any static host");
  c.Option("input", a.input, "A build directory (candi build), a demo's output, or a render archive (candi pack)")
      .Required();
  c.Option("-o,--output", a.output,
           "The site's folder (created; an earlier site there is updated in place, "
           "keeping every file publish did not write; a link is followed)")
      .Required();
  c.Option("-L,--repeat-level", o.repeat_level, "L of the data's pages and the page's default L (0: the scene's "
           "render setting, else 100)");
  c.Option("--group-points", o.group_points, "Points of consecutive chunks stored together (a file holds about "
           "this / L points)");
  c.Option("--memory-mb", o.memory_mb, "The page's default budget of points held, MB (16 bytes a point; the "
           "visitor can change it)");
  c.Option("--threads", o.threads, "Threads (0: all)");
  c.Option("--up", a.orientation.up, "World up for the first view, x,y,z (default 0,0,1)");
  c.Option("--from", a.orientation.from, "Direction the first view looks in, x,y,z (default: oblique, from above)");
  c.Option("--cameras", a.orientation.cameras, "A COLMAP model whose frame the points are in: the first view's up "
           "and side from its cameras");
  c.Run([&a] { return RunPublish(a); });
  c.Footer("Example: candi publish demo_out -o site && python3 -m http.server -d site 8000   (then open "
           "http://127.0.0.1:8000/)");
}

// ------------------------------------------------------------------------------------- section

struct SectionArgs {
  std::vector<std::string> inputs;    // an archive, a build directory, or point files
  std::string output;                 // a directory: section.png .dxf .csv .svg .json
  std::string plane;                  // px,py,pz,nx,ny,nz
  std::string through;                // x1,y1[,z1],x2,y2[,z2]: the vertical plane through two points
  std::string path;                   // x1,y1,x2,y2,...: an unrolled section along a plan polyline
  double thickness = 0;               // m, > 0
  pipeline::SectionOptions options;
  std::string colours = "layer";      // layer | data
  std::string background = "255,255,255";
  ClipArgs clip;
};

section::SectionPath ParseSection(const SectionArgs& a) {
  const int given = !a.plane.empty() + !a.through.empty() + !a.path.empty();
  if (given != 1) throw std::invalid_argument("give one of --plane, --through and --path");
  if (!a.plane.empty()) {
    const std::vector<double> v = ParseNumbers(a.plane, ',', "--plane");
    if (v.size() != 6) throw std::invalid_argument("--plane '" + a.plane + "': expected px,py,pz,nx,ny,nz");
    return section::SectionPath::Plane({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, a.thickness);
  }
  if (!a.through.empty()) {
    const std::vector<double> v = ParseNumbers(a.through, ',', "--through");
    if (v.size() == 4) return section::SectionPath::Through({v[0], v[1], 0}, {v[2], v[3], 0}, a.thickness);
    if (v.size() != 6) {
      throw std::invalid_argument("--through '" + a.through + "': expected x1,y1,x2,y2 or x1,y1,z1,x2,y2,z2");
    }
    return section::SectionPath::Through({v[0], v[1], v[2]}, {v[3], v[4], v[5]}, a.thickness);
  }
  const std::vector<double> v = ParseNumbers(a.path, ',', "--path");
  if (v.size() % 2 != 0) {
    throw std::invalid_argument("--path '" + a.path + "': expected x1,y1,x2,y2,... (plan vertices)");
  }
  std::vector<Eigen::Vector2d> plan;
  for (size_t i = 0; i + 1 < v.size(); i += 2) plan.push_back({v[i], v[i + 1]});
  size_t merged = 0;
  section::SectionPath s = section::SectionPath::Path(plan, a.thickness, &merged);
  if (merged > 0) LogWarning("--path: " + std::to_string(merged) + " repeated vertices merged");
  return s;
}

int RunSection(const SectionArgs& a) {
  const section::SectionPath path = ParseSection(a);
  const ClipRegion clip = ParseClip(a.clip.box, a.clip.planes);
  pipeline::SectionOptions o = a.options;
  if (a.colours != "layer" && a.colours != "data") {
    throw std::invalid_argument("--colours '" + a.colours + "': expected layer or data");
  }
  o.colours = a.colours == "data" ? pipeline::SectionColours::kData : pipeline::SectionColours::kLayer;
  o.background = ParseColour(a.background, "--background");
  const pipeline::SectionCut cut = pipeline::CutSection(o, a.inputs, path, clip);
  pipeline::WriteSection(cut, path, a.output);
  std::printf("%s: %s\n", a.output.c_str(), cut.describe.c_str());
  if (cut.archive) {
    std::printf("  read %llu of %llu chunks (%llu points)\n", static_cast<unsigned long long>(cut.chunks_read),
                static_cast<unsigned long long>(cut.chunks), static_cast<unsigned long long>(cut.points_read));
  }
  std::printf("  %-16s %10s %6s %10s\n", "layer", "points", "lines", "length m");
  for (const section::SectionLayerResult& l : cut.layers) {
    std::printf("  %-16s %10llu %6zu %10.3f%s\n", l.name.c_str(), static_cast<unsigned long long>(l.points),
                l.lines.size(), l.length, l.area ? "  (lies in the plane: no lines)" : "");
  }
  return kOk;
}

void AddSection(Command& root) {
  SectionArgs& a = root.Keep<SectionArgs>();
  pipeline::SectionOptions& o = a.options;
  Command c = root.Add("section", "Cut a slab out of an archive or point files: a see-through image of it and its "
                                  "section lines per layer (DXF, CSV, SVG), in survey coordinates");
  c.Option("inputs", a.inputs, "An archive (candi pack), a build directory (candi build), or point files (a file's "
           "layer field names its layers)").Required();
  c.Option("-o,--output", a.output, "Output directory: section.png, .dxf, .csv, .svg and .json").Required();
  c.Option("--plane", a.plane, "A plane through a point with a normal: px,py,pz,nx,ny,nz (world coordinates)");
  c.Option("--through", a.through, "The vertical plane through two survey points, chainage from the first: "
           "x1,y1,x2,y2 (or with z)");
  c.Option("--path", a.path, "A plan polyline x1,y1,x2,y2,...: its vertical faces unrolled into one section");
  c.Option("--thickness", a.thickness, "Slab thickness in metres (> 0)").Required();
  c.Option("--spacing", o.spacing, "Section lines: vertex spacing in metres (0: from the points' density)");
  c.Option("--max-gap", o.max_gap, "Section lines: a gap in the data longer than this breaks a line (0: automatic)");
  c.Option("--width", o.width, "Image width in pixels");
  c.Option("--pixel", o.pixel, "Image: metres per pixel (overrides --width)");
  c.Option("-L,--repeat-level", o.spbr.repeat_level, "Image: SPBR ensembles");
  c.Option("--seed", o.spbr.seed, "Image: seed of the ensembles");
  c.Option("--point-size", o.spbr.point_size, "Image: point size in pixels");
  c.Option("--opacity", o.opacity, "Image: opacity of a pixel one point covers, (0, 1]; overlapping layers blend as "
           "SPBR blends");
  c.Option("--colours", a.colours, "Image colours: layer (one per layer) or data (the points' own)");
  c.Option("--background", a.background, "Image background r,g,b");
  c.Option("--layers", o.layers, "Only these layers (names)").Delimiter(',');
  c.Option("--columns", o.columns, "XYZ/PTS column spec");
  c.Option("--threads", o.threads, "Threads (0: all)").Range(0, 256);
  AddClip(c, a.clip);
  c.Run([&a] { return RunSection(a); });
  c.Footer("Example: candi section borobudur_out/ --through 0,-60,0,60 --thickness 0.2 -o section_ns/");
}

}  // namespace

void AddLookCommands(Command& root) {
  AddRender(root);
  AddView(root);
  AddPublish(root);
  AddSection(root);
}

}  // namespace candi::apps

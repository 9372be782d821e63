// candi view, publish: the browser viewer (view/: a build directory, an archive or point files
// served until Ctrl-C; under mpirun every rank draws a share of each image) and the static web
// site that renders the archive in the visitor's browser (view/publish.h).
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
#include <vector>

#include "apps/commands.h"
#include "apps/failure.h"
#include "apps/option_groups.h"
#include "core/check.h"
#include "core/interrupt.h"
#include "core/log.h"
#include "core/progress.h"
#include "pipeline/section.h"
#include "render/archive.h"
#include "render/mpi/archive_ranks.h"
#include "render/mpi/mpi_session.h"
#include "view/publish.h"
#include "view/server.h"
#include "view/source.h"

namespace candi::apps {

namespace {

namespace fs = std::filesystem;

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
    render::mpi::ServeArchiveRequests(*session, a.server.threads, DescribeFailureForMpi);
    return kOk;
  }
  OpenedSource opened;
  const render::Orientation orientation = ParseOrientation(a.orientation);
  const bool previewed = OpenSource(a, orientation, /*allow_preview=*/!session, &opened);
  view::ViewerSource& source = opened.source;
  source.settings.clip = ParseClip(a.clip);
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
      return render::mpi::RenderRequestShare(*session, archive, request, threads, DescribeFailureForMpi);
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

}  // namespace

void AddView(Command& root) {
  ViewArgs& a = root.Keep<ViewArgs>();
  Command c = root.Add("view", "Open an archive in the browser: orbit it see-through while the server renders "
                               "(SPBR), the image refining as you watch");
  c.Option("inputs", a.inputs, "A build directory (candi build), a render archive (candi pack), or point files "
           "(packed on the fly into a temporary archive)").Required();
  c.Option("--host", a.server.host, "Address to serve on (default 127.0.0.1; 0.0.0.0 serves your network: anyone "
           "with the printed address and token sees the data)");
  c.Option("--port", a.port, "Port (0: any free one)").Range(0, 65535);
  AddOrientation(c, a.orientation,
                 {"World up for the first view, x,y,z (default 0,0,1; COLMAP's frame: 0,-1,0)",
                  "Direction the first view looks in, x,y,z (default: oblique, from above)",
                  "A COLMAP model (e.g. WORK/sparse/0) whose frame the points are in: the first view's up and side "
                  "from its cameras"});
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

namespace {

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

}  // namespace

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
  AddOrientation(c, a.orientation,
                 {"World up for the first view, x,y,z (default 0,0,1)",
                  "Direction the first view looks in, x,y,z (default: oblique, from above)",
                  "A COLMAP model whose frame the points are in: the first view's up and side from its cameras"});
  c.Run([&a] { return RunPublish(a); });
  c.Footer("Example: candi publish demo_out -o site && python3 -m http.server -d site 8000   (then open "
           "http://127.0.0.1:8000/)");
}

}  // namespace candi::apps

#include "pipeline/viewer.h"

#include <exception>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>

#include "core/check.h"
#include "core/interrupt.h"
#include "core/log.h"
#include "pipeline/section.h"
#include "render/archive.h"
#include "render/mpi/mpi_session.h"
#include "view/source.h"

namespace candi::pipeline {

void ViewerOptions::Check() const {
  server.Check();
  CANDI_CHECK_OPTION_IN(port, 0, 65535);
  colour_by.Check();
}

namespace {

namespace fs = std::filesystem;

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

// Opens the source; for point files of more than twice `o.preview` points whose points are
// records (and no colouring by a field, `allow_preview`), a preview's archive, and returns true:
// the caller then packs every point (PackWhole) while the preview is served.
bool OpenSource(const ViewerOptions& o, const std::vector<std::string>& inputs,
                const render::Orientation& orientation, bool allow_preview,
                const TaskProgress& progress, OpenedSource* opened) {
  std::error_code ec;
  if (inputs.size() == 1 && fs::is_directory(inputs[0], ec)) {
    if (o.colour_by.active()) {
      throw std::invalid_argument(
          "--colour-by needs point files: " + inputs[0] +
          " is an archive or a build, which holds the points' colours, not their fields");
    }
    opened->source = view::OpenViewerSource(inputs[0], orientation);
    return false;
  }
  for (const std::string& in : inputs) {
    if (fs::is_directory(in, ec))
      throw std::invalid_argument(in + " is a directory: open it alone");
  }
  if (allow_preview && o.preview > 0 && !o.colour_by.active() &&
      view::PreviewEvery(inputs, o.columns, o.preview) > 0) {
    std::optional<view::ViewerSource> preview;
    {
      ProgressTask task(progress,
                        "view: packing a preview of " + std::to_string(o.preview) + " points");
      preview = view::PackPreviewSource(inputs, o.columns, orientation, o.preview, task.callback());
    }
    CANDI_CHECK(preview.has_value()) << "PreviewEvery promised a preview";
    opened->source = std::move(*preview);
    return true;
  }
  ProgressTask task(progress, "view: packing " + std::to_string(inputs.size()) + " point file(s)");
  opened->source =
      view::PackViewerSource(inputs, o.columns, orientation, task.callback(), o.colour_by);
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
  PackWhole(const ViewerOptions& o, const std::vector<std::string>& inputs,
            const render::Orientation& orientation, const TaskProgress& progress, uint64_t points,
            view::Server* server, Current* current)
      : thread_([=, &o, &inputs, &progress] {
          try {
            {
              ProgressTask task(progress,
                                "view: packing all " + std::to_string(points) + " points");
              whole_.source =
                  view::PackViewerSource(inputs, o.columns, orientation, task.callback());
            }
            whole_.source.settings.clip = o.clip;
            archive_ = std::make_unique<render::Archive>(whole_.source.archive_dir);
            current->Set(&whole_.source, archive_.get());
            server->Replace(whole_.source, *archive_, view::LocalRangeRenderer(*archive_));
            LogInfo("view: all " + std::to_string(archive_->manifest().points) +
                    " points packed: the pages show them");
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

// A page's section export, from the archive drawn when it arrives.
decltype(view::ServerOptions::section) SectionExporter(Current* current, int threads) {
  return [current, threads](uint64_t seq, const view::SectionRequest& r,
                            const view::ViewState& state, const view::SectionControl& control) {
    SectionOptions o;
    o.threads = threads;
    o.max_points = control.max_points;
    o.checkpoint = control.checkpoint;
    const auto [drawn, drawn_archive] = current->Get();
    return ExportViewerSection(drawn->archive_dir, drawn_archive->manifest(), o, seq, r, state);
  };
}

// However rank 0 leaves, the other ranks stop serving.
struct StopRanks {
  const render::mpi::Session* session = nullptr;
  ~StopRanks() {
    std::string stop = render::mpi::kStopRequest;
    if (session) session->Broadcast(&stop);
  }
};

// Under mpirun: the archive's folder to the other ranks, and a renderer that has every rank
// draw its share of each step.
view::RangeRenderer RanksRenderer(const render::mpi::Session& session,
                                  const view::ViewerSource& source, const render::Archive& archive,
                                  int threads, const render::mpi::FailureDescriber& describe) {
  std::string dir = fs::absolute(source.archive_dir).string();
  session.Broadcast(&dir);
  LogInfo("view: " + std::to_string(session.size()) +
          " MPI ranks share every image's ensembles (the archive must "
          "be at the same path on every rank's machine)");
  return [&session, &archive, threads, describe](const render::ArchiveRenderOptions& o,
                                                 const render::Camera& camera,
                                                 const std::function<bool()>&) {
    std::string request = render::mpi::EncodeArchiveRequest(o, camera);
    session.Broadcast(&request);
    return render::mpi::RenderRequestShare(session, archive, request, threads, describe);
  };
}

// The server on the usual port, or the next free one (as Jupyter does); an explicit port or 0
// as given.
std::unique_ptr<view::Server> StartServer(view::ServerOptions options, int port,
                                          const view::ViewerSource& source,
                                          const render::Archive& archive,
                                          const view::RangeRenderer& renderer) {
  std::unique_ptr<view::Server> server;
  const int tries = port == kViewerPort ? 20 : 1;
  for (int i = 0; i < tries && !server; ++i) {
    options.port = port == 0 ? 0 : port + i;
    try {
      server = std::make_unique<view::Server>(options, source, archive, renderer);
    } catch (const std::runtime_error& e) {
      if (i + 1 == tries) throw InputError(e.what());
    }
  }
  return server;
}

}  // namespace

void ServeViewer(const ViewerOptions& o, const std::vector<std::string>& inputs,
                 const ViewerCallbacks& callbacks) {
  o.Check();  // before the source is opened (or packed)
  std::unique_ptr<render::mpi::Session> session;
  if (render::mpi::LaunchedByMpi())
    session = std::make_unique<render::mpi::Session>(/*serialized=*/true);
  if (session && session->rank() != 0) {
    render::mpi::ServeArchiveRequests(*session, o.server.threads, callbacks.describe);
    return;
  }
  OpenedSource opened;
  const render::Orientation orientation = o.orientation.Resolve();
  const bool previewed =
      OpenSource(o, inputs, orientation, /*allow_preview=*/!session, callbacks.progress, &opened);
  view::ViewerSource& source = opened.source;
  source.settings.clip = o.clip;
  const render::Archive archive(source.archive_dir);
  Current current;
  current.Set(&source, &archive);
  StopRanks stop_ranks;
  view::RangeRenderer renderer = view::LocalRangeRenderer(archive);
  if (session) {
    renderer = RanksRenderer(*session, source, archive, o.server.threads, callbacks.describe);
    stop_ranks.session = session.get();
  }
  view::ServerOptions options = o.server;
  options.log = [](const std::string& line) { LogInfo(line); };
  options.section = SectionExporter(&current, o.server.threads);
  if (o.server.host != "127.0.0.1" && o.server.host != "localhost" && o.server.host != "::1") {
    LogWarning("serving on " + o.server.host +
               ": anyone who can reach this machine and has the address with its "
               "token sees the data; the connection is not encrypted");
  }
  // Declared before the server: the whole archive, once served, must outlive it.
  std::optional<PackWhole> whole;
  const std::unique_ptr<view::Server> server =
      StartServer(options, o.port, source, archive, renderer);
  LogInfo("view: " + source.title + " (" + source.kind + ", " +
          std::to_string(archive.manifest().points) + " points in " +
          std::to_string(archive.manifest().chunks.size()) + " chunks" +
          (previewed ? ": a preview, one point in " + std::to_string(source.preview_every) +
                           " of " + std::to_string(source.preview_points) + ", until all are packed"
                     : "") +
          "); Ctrl-C stops");
  if (callbacks.serving) callbacks.serving(*server);
  if (previewed)
    whole.emplace(o, inputs, orientation, callbacks.progress, source.preview_points, server.get(),
                  &current);
  try {
    server->Run();
  } catch (...) {
    if (whole) whole->Join();  // before the server goes
    throw;
  }
  if (whole) whole->Finish();  // a failure to pack every point: its error
}

}  // namespace candi::pipeline

// candi view INPUT...: parses the command and hands it to view/ (the server, the page).
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "core/interrupt.h"
#include "core/log.h"
#include "core/progress.h"
#include "render/archive.h"
#include "render/mpi/mpi_session.h"
#include "view/server.h"
#include "view/source.h"

namespace candi::app {

namespace {

Eigen::Vector3d ParseDirection(const std::string& text, const std::string& what) {
  const std::vector<double> v = ParseNumbers(text, ',', what);
  if (v.size() != 3) throw std::invalid_argument(what + " '" + text + "': expected x,y,z");
  const Eigen::Vector3d d(v[0], v[1], v[2]);
  if (!(d.norm() > 0) || !d.allFinite()) throw std::invalid_argument(what + " '" + text + "': not a direction");
  return d;
}

}  // namespace

int RunView(const ViewArgs& args) {
  if (render::mpi::LaunchedByMpi()) {
    throw std::invalid_argument("candi view serves from one process; under mpirun use candi render");
  }
  view::Orientation orientation;
  if (!args.up.empty()) orientation.up = ParseDirection(args.up, "--up");
  if (!args.from.empty()) orientation.view_dir = ParseDirection(args.from, "--from");
  if (orientation.view_dir && orientation.view_dir->normalized().cross(orientation.up.normalized()).norm() < 1e-3) {
    throw std::invalid_argument("--from is parallel to --up: the view would have no up");
  }
  view::ViewerSource source;
  namespace fs = std::filesystem;
  std::error_code ec;
  const bool one_dir = args.inputs.size() == 1 && fs::is_directory(args.inputs[0], ec);
  int temporary = -1;
  if (one_dir) {
    source = view::OpenViewerSource(args.inputs[0], orientation);
  } else {
    for (const std::string& in : args.inputs) {
      if (fs::is_directory(in, ec)) throw std::invalid_argument(in + " is a directory: open it alone");
    }
    ConsoleProgress progress("view: packing " + std::to_string(args.inputs.size()) + " point file(s)");
    source = view::PackViewerSource(args.inputs, args.columns, orientation, progress.Callback());
    progress.Finish();
    temporary = RegisterTempPath(source.temporary_dir);  // removed on Ctrl-C, or below
  }
  struct Cleanup {
    std::string dir;
    int id;
    ~Cleanup() {
      if (dir.empty()) return;
      std::error_code ignored;
      std::filesystem::remove_all(dir, ignored);
      UnregisterTempPath(id);
    }
  } cleanup{source.temporary_dir, temporary};

  const render::Archive archive(source.archive_dir);
  view::ServerOptions options;
  options.host = args.host;
  options.threads = args.threads;
  options.log = [](const std::string& line) { LogInfo(line); };
  if (args.host != "127.0.0.1" && args.host != "localhost" && args.host != "::1") {
    LogWarning("serving on " + args.host + ": anyone who can reach this machine and has the address with its token "
               "sees the data; the connection is not encrypted");
  }
  // The default port, or the next free one (as Jupyter does); an explicit port or 0 as given.
  std::unique_ptr<view::Server> server;
  const int tries = args.port == 8765 ? 20 : 1;
  for (int i = 0; i < tries && !server; ++i) {
    options.port = args.port == 0 ? 0 : args.port + i;
    try {
      server = std::make_unique<view::Server>(options, source, archive, view::LocalRangeRenderer(archive));
    } catch (const std::runtime_error& e) {
      if (i + 1 == tries) throw InputError(e.what());
    }
  }
  LogInfo("view: " + source.title + " (" + source.kind + ", " + std::to_string(archive.manifest().points) +
          " points in " + std::to_string(archive.manifest().chunks.size()) + " chunks); Ctrl-C stops");
  std::printf("candi view: %s\n", server->Url().c_str());
  std::fflush(stdout);
  server->Run();
  return kOk;
}

}  // namespace candi::app

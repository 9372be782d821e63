// candi view INPUT...: parses the command and hands it to view/ (the server, the page).
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "apps/failure.h"
#include "apps/view_orientation.h"
#include "core/interrupt.h"
#include "core/log.h"
#include "core/progress.h"
#include "render/archive.h"
#include "render/mpi/mpi_session.h"
#include "render/view_json.h"
#include "view/server.h"
#include "view/source.h"

namespace candi::app {

namespace {


// Under mpirun: rank 0 serves; for every step it broadcasts the request (camera, ensembles,
// settings), every rank draws its share of the ensembles, and the sums are added on rank 0
// exactly as candi render does. A rank's failure reaches rank 0 (the page gets the error); the
// other ranks go on serving.
std::string EncodeRequest(const render::ArchiveRenderOptions& o, const render::Camera& local) {
  const nlohmann::json j = {{"camera", nlohmann::json::parse(render::ViewToJson(local))},
                            {"repeat_level", o.repeat_level},
                            {"seed", o.seed},
                            {"point_size", o.point_size},
                            {"begin", o.ensemble_begin},
                            {"end", o.ensemble_end},
                            {"layers", o.layer_fraction},
                            {"clip", view::ClipPlaneArrays(o.clip)},  // doubles travel exactly (17 digits)
                            {"verify", o.verify}};
  return j.dump();
}

render::SpbrResult DrawShare(const render::mpi::Session& session, const render::Archive& archive,
                             const std::string& request, int threads) {
  render::SpbrResult result;
  std::exception_ptr failure;
  try {
    const nlohmann::json j = nlohmann::json::parse(request);
    const render::Camera camera = render::ParseView(j.at("camera").dump(), "request");
    render::ArchiveRenderOptions o;
    o.repeat_level = j.at("repeat_level").get<int>();
    o.seed = j.at("seed").get<uint64_t>();
    o.point_size = j.at("point_size").get<double>();
    o.layer_fraction = j.at("layers").get<std::vector<double>>();
    for (const auto& p : j.at("clip")) {
      o.clip.planes.push_back({Eigen::Vector3d(p[0].get<double>(), p[1].get<double>(), p[2].get<double>()),
                               Eigen::Vector3d(p[3].get<double>(), p[4].get<double>(), p[5].get<double>())});
    }
    o.verify = j.at("verify").get<bool>();
    o.threads = threads;
    const int begin = j.at("begin").get<int>(), end = j.at("end").get<int>();
    int b = 0, e = 0;
    render::mpi::EnsembleShare(end - begin, session.rank(), session.size(), &b, &e);
    o.ensemble_begin = begin + b;
    o.ensemble_end = begin + e;
    result.sums = render::Accumulator(camera.width, camera.height);
    if (e > b) result = render::RenderArchive(o, camera, archive);
  } catch (...) {
    failure = std::current_exception();
  }
  const FailureReport mine = failure ? DescribeFailure(failure) : FailureReport{};
  const auto failures = session.GatherFailures(mine.exit_code, mine.text);
  if (!failures.empty()) {
    throw InputError("MPI rank " + std::to_string(failures.front().rank) + " of " + std::to_string(session.size()) +
                     " failed: " + failures.front().message);
  }
  session.ReduceToRoot(&result);
  return result;
}

// Ranks other than 0: the archive rank 0 opened, then requests until "stop".
int ServeRank(const render::mpi::Session& session, int threads) {
  SetConsoleProgressEnabled(false);
  std::string dir;
  session.Broadcast(&dir);
  const render::Archive archive(dir);
  for (;;) {
    std::string request;
    session.Broadcast(&request);
    if (request == "stop") return kOk;
    try {
      DrawShare(session, archive, request, threads);
    } catch (const InputError&) {  // reported by rank 0
    }
  }
}

std::string Base64(const std::string& bytes) {
  static const char* kDigits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (size_t i = 0; i < bytes.size(); i += 3) {
    uint32_t n = static_cast<uint8_t>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) n |= static_cast<uint8_t>(bytes[i + 1]) << 8;
    if (i + 2 < bytes.size()) n |= static_cast<uint8_t>(bytes[i + 2]);
    out += kDigits[n >> 18 & 63];
    out += kDigits[n >> 12 & 63];
    out += i + 1 < bytes.size() ? kDigits[n >> 6 & 63] : '=';
    out += i + 2 < bytes.size() ? kDigits[n & 63] : '=';
  }
  return out;
}

std::string ReadWhole(const std::filesystem::path& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(path.string(), "", "cannot read the section output");
  std::string out;
  char buffer[65536];
  size_t n;
  while ((n = std::fread(buffer, 1, sizeof(buffer), f)) > 0) out.append(buffer, n);
  std::fclose(f);
  return out;
}

// The page's "export section": candi section of the archive for the slab, with the page's
// clipping and only its shown layers, written to a temporary directory whose files travel back
// in the reply (the PNG as base64).
std::string SectionReply(const std::string& archive_dir, const render::ArchiveManifest& m, int threads, uint64_t seq,
                         const view::SectionRequest& r, const view::ViewState& state) {
  namespace fs = std::filesystem;
  SectionArgs a;
  a.inputs = {archive_dir};
  a.thickness = r.thickness;
  a.threads = threads;
  const std::vector<double>& f = state.settings.layer_fraction;
  for (size_t k = 0; k < f.size() && k < m.layers.size(); ++k) {
    if (f[k] > 0) a.layers.push_back(m.layers[k].name);
  }
  if (!f.empty() && a.layers.empty()) throw std::invalid_argument("every layer is hidden");
  if (a.layers.size() == m.layers.size()) a.layers.clear();
  std::string pattern = (fs::temp_directory_path() / "candi-view-section-XXXXXX").string();
  if (!mkdtemp(pattern.data())) throw InputError(pattern, "", "cannot create a temporary directory");
  struct Remove {
    std::string dir;
    ~Remove() {
      std::error_code ignored;
      fs::remove_all(dir, ignored);
    }
  } remove{pattern};
  a.output = pattern;
  const std::string summary =
      RunSectionInto(a, section::SectionPath::Plane(r.point, r.normal, r.thickness), state.settings.clip, /*print=*/false);
  const fs::path out(pattern);
  return nlohmann::json{{"type", "section"},
                        {"seq", seq},
                        {"summary", nlohmann::json::parse(summary)},
                        {"dxf", ReadWhole(out / "section.dxf")},
                        {"svg", ReadWhole(out / "section.svg")},
                        {"csv", ReadWhole(out / "section.csv")},
                        {"png_base64", Base64(ReadWhole(out / "section.png"))}}
      .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

}  // namespace

int RunView(const ViewArgs& args) {
  std::unique_ptr<render::mpi::Session> session;
  if (render::mpi::LaunchedByMpi()) session = std::make_unique<render::mpi::Session>(/*serialized=*/true);
  if (session && session->rank() != 0) return ServeRank(*session, args.threads);
  const view::Orientation orientation = ParseOrientation(args.up, args.from, args.cameras);
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

  source.settings.clip = ParseClip(args.clip.box, args.clip.planes);
  const render::Archive archive(source.archive_dir);
  view::RangeRenderer renderer = view::LocalRangeRenderer(archive);
  std::string stop = "stop";
  struct StopRanks {  // however rank 0 leaves, the other ranks stop serving
    render::mpi::Session* session;
    std::string* stop;
    ~StopRanks() {
      if (session) session->Broadcast(stop);
    }
  } stop_ranks{nullptr, &stop};
  if (session) {
    std::string dir = std::filesystem::absolute(source.archive_dir).string();
    session->Broadcast(&dir);
    stop_ranks.session = session.get();
    renderer = [&session, &archive, threads = args.threads](const render::ArchiveRenderOptions& o,
                                                           const render::Camera& camera,
                                                           const std::function<bool()>&) {
      std::string request = EncodeRequest(o, camera);
      session->Broadcast(&request);
      return DrawShare(*session, archive, request, threads);
    };
    LogInfo("view: " + std::to_string(session->size()) + " MPI ranks share every image's ensembles (the archive must "
            "be at the same path on every rank's machine)");
  }
  view::ServerOptions options;
  options.host = args.host;
  options.threads = args.threads;
  options.log = [](const std::string& line) { LogInfo(line); };
  options.section = [&source, &archive, threads = args.threads](uint64_t seq, const view::SectionRequest& r,
                                                                const view::ViewState& state) {
    return SectionReply(source.archive_dir, archive.manifest(), threads, seq, r, state);
  };
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
      server = std::make_unique<view::Server>(options, source, archive, renderer);
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

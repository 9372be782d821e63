// COLMAP as child processes. Option names are COLMAP 3.8's (checked with `colmap <command> -h`).
#include "reconstruction/photogrammetry/sfm/colmap_runner.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/interrupt.h"
#include "core/log.h"
#include "reconstruction/photogrammetry/sfm/colmap_database.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"
#include "reconstruction/photogrammetry/sfm/sift_matching.h"

extern char** environ;

namespace candi::photogrammetry {

namespace fs = std::filesystem;

namespace {

constexpr const char* kModelPlaceholder = "<model>";
constexpr const char* kMatchList = "matches.txt";
constexpr double kHeartbeatSeconds = 10.0;
constexpr int kLogTailLines = 20;

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool IsImageName(const std::string& name) {
  static const std::set<std::string> kExtensions = {".jpg", ".jpeg", ".png", ".tif", ".tiff",
                                                    ".bmp", ".pgm",  ".ppm", ".pnm"};
  return kExtensions.count(Lower(fs::path(name).extension().string())) > 0;
}

std::string Path(const std::string& workspace, const std::string& relative) {
  return (fs::path(workspace) / relative).string();
}

std::string Threads(int threads) { return std::to_string(threads); }

// Outputs of a previous run; refused unless overwriting, then removed (never the input photos:
// images/ holds only our symlinks).
void PrepareWorkspace(const SfmOptions& options, const std::string& workspace,
                      const std::string& images_dir) {
  std::error_code ec;
  fs::create_directories(workspace, ec);
  if (ec) throw InputError(workspace, "", "cannot create the workspace folder: " + ec.message());
  if (fs::equivalent(fs::path(images_dir), Path(workspace, "images"), ec)) {
    throw InputError(images_dir, "", "the photos must not be the workspace's own images/ folder "
                                     "(candi fills it with links); choose another workspace");
  }
  std::vector<std::string> previous;
  for (const char* entry : {"database.db", kMatchList, "images", "sparse", "dense", "logs", "sfm_report.json", "chunks",
                            "sparse_chunks"}) {
    if (fs::exists(fs::symlink_status(Path(workspace, entry)))) previous.push_back(entry);
  }
  if (previous.empty()) return;
  if (!options.overwrite) {
    std::string list;
    for (const std::string& p : previous) list += (list.empty() ? "" : ", ") + p;
    throw InputError(workspace, "", "holds a previous run (" + list +
                                        "); pass --overwrite to replace it, or choose another folder");
  }
  for (const std::string& p : previous) {
    fs::remove_all(Path(workspace, p), ec);
    if (ec) throw InputError(Path(workspace, p), "", "cannot remove: " + ec.message());
  }
}

void LinkImages(const std::string& images_dir, const std::vector<std::string>& names,
                const std::string& workspace) {
  const fs::path target_dir = fs::absolute(images_dir);
  const fs::path links = Path(workspace, "images");
  fs::create_directories(links);
  for (const std::string& name : names) {
    std::error_code ec;
    fs::create_directories((links / name).parent_path(), ec);
    fs::create_symlink(target_dir / name, links / name, ec);
    if (ec) throw InputError((links / name).string(), "", "cannot create a link: " + ec.message());
  }
}

// The mapper's model with the most registered images, "" when there is none.
std::string LargestModel(const std::string& sparse_dir, ColmapModel* best) {
  std::string best_dir;
  std::error_code ec;
  std::vector<fs::path> dirs;
  for (const auto& entry : fs::directory_iterator(sparse_dir, ec)) {
    if (entry.is_directory()) dirs.push_back(entry.path());
  }
  std::sort(dirs.begin(), dirs.end());
  for (const fs::path& dir : dirs) {
    if (!fs::exists(dir / "cameras.bin") && !fs::exists(dir / "cameras.txt")) continue;
    ColmapModel model = ReadColmapModel(dir.string());
    if (best_dir.empty() || model.images.size() > best->images.size()) {
      *best = std::move(model);
      best_dir = dir.string();
    }
  }
  return best_dir;
}

void Summarize(const ColmapModel& model, SfmSummary* summary) {
  for (const auto& [id, image] : model.images) summary->registered.push_back(image.name);
  std::sort(summary->registered.begin(), summary->registered.end());
  summary->points = model.points3d.size();
  summary->mean_reprojection_error = MeanReprojectionError(model);
  size_t observations = 0;
  for (const auto& [id, point] : model.points3d) observations += point.track.size();
  summary->mean_track_length =
      model.points3d.empty() ? 0.0 : static_cast<double>(observations) / model.points3d.size();
}

std::string ArgvText(const std::vector<std::string>& argv) {
  std::string text;
  for (const std::string& a : argv) text += (text.empty() ? "" : " ") + a;
  return text;
}

}  // namespace

void SfmOptions::Check() const {
  CANDI_CHECK_OPTION_MSG(!colmap.empty(), colmap, "must name the COLMAP executable");
  CANDI_CHECK_OPTION_GE(max_image_size, 64);
  CANDI_CHECK_OPTION_GE(max_features, 64);
  pairs.Check();
  CANDI_CHECK_OPTION(CameraModelId(camera_model) >= 0, camera_model,
                     "a COLMAP camera model (SIMPLE_RADIAL, OPENCV, ...)");
  CANDI_CHECK_OPTION(threads == -1 || threads >= 1, threads, "-1 (all) or >= 1");
  chunks.Check();
}

ColmapVersion ParseColmapVersion(const std::string& help_output) {
  static const std::regex kBanner(R"(COLMAP\s+([0-9][0-9A-Za-z.\-]*))");
  std::smatch match;
  if (!std::regex_search(help_output, match, kBanner)) {
    throw std::invalid_argument("not COLMAP's banner: '" + help_output.substr(0, 120) + "'");
  }
  ColmapVersion version;
  version.version = match[1];
  // Only the banner (before "Usage:") decides; the command list mentions no CUDA.
  const std::string banner = help_output.substr(0, help_output.find("Usage"));
  version.cuda = banner.find("with CUDA") != std::string::npos &&
                 banner.find("without CUDA") == std::string::npos;
  return version;
}

std::vector<SfmStage> BuildSfmStages(const SfmOptions& options, const std::string& workspace, bool cuda) {
  options.Check();
  const std::string& exe = options.colmap;
  const std::string database = Path(workspace, "database.db"), images = Path(workspace, "images");
  const std::string gpu = cuda ? "1" : "0";
  std::vector<SfmStage> stages;
  stages.push_back({"feature_extractor",
                    {exe, "feature_extractor", "--database_path", database, "--image_path", images,
                     "--ImageReader.camera_model", options.camera_model,
                     "--ImageReader.single_camera", options.single_camera ? "1" : "0",
                     "--SiftExtraction.max_image_size", std::to_string(options.max_image_size),
                     "--SiftExtraction.max_num_features", std::to_string(options.max_features),
                     "--SiftExtraction.num_threads", Threads(options.threads),
                     "--SiftExtraction.use_gpu", gpu}});
  // Matching is candi's (sift_matching.h; an in-process stage, no argv); COLMAP verifies the
  // matches (one thread, in the list's order) and maps with one thread and its PRNG seeded, so
  // the same photos give the same model on every run.
  stages.push_back({kMatchStage, {}});
  stages.push_back({"matches_importer",
                    {exe, "matches_importer", "--database_path", database, "--match_list_path",
                     Path(workspace, kMatchList), "--match_type", "raw", "--SiftMatching.use_gpu", "0",
                     "--SiftMatching.num_threads", "1", "--random_seed", "0"}});
  stages.push_back({"mapper",
                    {exe, "mapper", "--database_path", database, "--image_path", images,
                     "--output_path", Path(workspace, "sparse"), "--Mapper.num_threads", "1",
                     "--random_seed", "0"}});
  stages.push_back({"image_undistorter",
                    {exe, "image_undistorter", "--image_path", images, "--input_path",
                     kModelPlaceholder, "--output_path", Path(workspace, "dense"), "--output_type",
                     "COLMAP", "--max_image_size", std::to_string(options.max_image_size)}});
  return stages;
}

namespace {

// Image files directly in `dir` (names prefixed by `prefix`), other files to `ignored`.
void ListFolder(const fs::path& dir, const std::string& prefix, std::vector<std::string>* images,
                std::vector<std::string>* ignored, std::vector<std::string>* folders) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_directory()) {
      if (folders != nullptr) folders->push_back(name);
      continue;
    }
    if (!entry.is_regular_file()) continue;  // follows symlinks
    if (IsImageName(name)) {
      images->push_back(prefix + name);
    } else if (ignored != nullptr) {
      ignored->push_back(prefix + name);
    }
  }
  if (ec) throw InputError(dir.string(), "", "cannot list the folder: " + ec.message());
}

}  // namespace

std::vector<std::string> ListImages(const std::string& dir, std::vector<std::string>* ignored) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw InputError(dir, "", fs::exists(dir, ec) ? "is not a folder (give the folder of photos)"
                                                  : "no such folder");
  }
  std::vector<std::string> images, folders;
  ListFolder(dir, "", &images, ignored, &folders);
  if (images.empty()) {  // a campaign: one folder a session
    std::sort(folders.begin(), folders.end());
    for (const std::string& folder : folders) ListFolder(fs::path(dir) / folder, folder + "/", &images, ignored, nullptr);
  }
  std::sort(images.begin(), images.end());
  if (ignored != nullptr) std::sort(ignored->begin(), ignored->end());
  return images;
}

int RunLogged(const std::vector<std::string>& argv, const std::string& log_path,
              const std::function<void(double seconds)>& heartbeat) {
  CANDI_CHECK(!argv.empty());
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log_path.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  // The child starts with no signal blocked (candi's interrupt handler blocks them in its own
  // threads, core/interrupt.h) and is stopped with candi when it is interrupted.
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t mask;
  ChildSignalMask(&mask);
  posix_spawnattr_setsigmask(&attributes, &mask);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGMASK);
  pid_t pid = 0;
  const int err = posix_spawnp(&pid, args[0], &actions, &attributes, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (err != 0) {
    throw InputError(argv[0], "", std::string("cannot run: ") + std::strerror(err) +
                                      " (log: " + log_path + ")");
  }
  struct Registered {
    int id;
    ~Registered() { UnregisterChild(id); }
  } registered{RegisterChild(pid)};
  const auto start = std::chrono::steady_clock::now();
  double next_beat = kHeartbeatSeconds;
  int status = 0;
  for (;;) {
    const pid_t r = waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) throw InputError(argv[0], "", std::string("waitpid: ") + std::strerror(errno));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (heartbeat && seconds >= next_beat) {
      heartbeat(seconds);
      next_beat += kHeartbeatSeconds;
    }
  }
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

void ParseFeatureExtractionLog(const std::string& log_path, SfmSummary* summary) {
  std::ifstream in(log_path);
  std::string line, name;
  while (std::getline(in, line)) {
    const size_t name_at = line.find("Name:");
    if (name_at != std::string::npos) {
      std::istringstream(line.substr(name_at + 5)) >> name;
      continue;
    }
    if (line.find("ERROR: Failed to read image") != std::string::npos) {
      summary->unreadable.push_back(name);
      continue;
    }
    const size_t focal_at = line.find("Focal Length:");
    if (focal_at == std::string::npos || line.find("(Prior)") != std::string::npos) continue;
    summary->no_exif.push_back(name);
    std::istringstream(line.substr(focal_at + 13)) >> summary->default_focal_px;
  }
  // The extractor's threads log the photos in the order they finish: sorted, the lists are the
  // same bytes on every run.
  std::sort(summary->no_exif.begin(), summary->no_exif.end());
  std::sort(summary->unreadable.begin(), summary->unreadable.end());
}

double RunSfmStage(const SfmStage& stage, const std::string& log_path, int index, int count,
                const SfmProgress& progress) {
  if (progress) progress(stage.name, index, count, 0.0, false);
  WriteFileAtomic(log_path, "$ " + ArgvText(stage.argv) + "\n");
  const auto start = std::chrono::steady_clock::now();
  const int code = RunLogged(stage.argv, log_path, [&](double seconds) {
    if (progress) progress(stage.name, index, count, seconds, false);
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (code != 0) {
    const std::string how = code > 128 ? "was killed by signal " + std::to_string(code - 128)
                                       : "failed with exit code " + std::to_string(code);
    throw InputError(log_path, "", "colmap " + stage.name + " " + how + "; the end of its log:\n" +
                                       TailOfFile(log_path, kLogTailLines));
  }
  if (progress) progress(stage.name, index, count, seconds, true);
  return seconds;
}

std::string TailOfFile(const std::string& path, int lines) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "";
  std::vector<std::string> kept;
  std::string line;
  while (std::getline(in, line)) {
    // COLMAP redraws some lines with '\r'; keep the last state of each.
    const size_t cr = line.find_last_of('\r', line.size() >= 2 ? line.size() - 2 : 0);
    if (cr != std::string::npos && cr + 1 < line.size()) line = line.substr(cr + 1);
    if (line.empty() || line.rfind("    @ ", 0) == 0) continue;  // glog stack-trace frames
    kept.push_back(line);
    if (kept.size() > static_cast<size_t>(lines)) kept.erase(kept.begin());
  }
  std::string text;
  for (const std::string& l : kept) text += l + "\n";
  return text;
}

namespace {

// After feature extraction: photos COLMAP could not decode are skipped (a warning), unless fewer
// than two remain.
void CheckExtraction(const std::string& log_path, const std::string& images_dir, SfmSummary* summary) {
  ParseFeatureExtractionLog(log_path, summary);
  if (summary->unreadable.empty()) return;
  std::string list;
  for (const std::string& name : summary->unreadable) list += (list.empty() ? "" : ", ") + name;
  if (summary->images.size() - summary->unreadable.size() < 2) {
    throw InputError(images_dir, "", "COLMAP could not read " + std::to_string(summary->unreadable.size()) +
                                         " of the " + std::to_string(summary->images.size()) +
                                         " images (" + list + "): corrupt or not images; fewer than "
                                         "2 usable photos remain (see " + log_path + ")");
  }
  LogWarning("COLMAP could not read (skipped): " + list);
}

ColmapVersion DetectColmap(const std::string& colmap, const std::string& log_path) {
  WriteFileAtomic(log_path, "");
  int code = -1;
  try {
    code = RunLogged({colmap, "help"}, log_path);
  } catch (const InputError& e) {
    throw InputError("COLMAP was not found: '" + colmap + "' cannot be run (" + e.what() +
                     "). Install it (Debian/Ubuntu: sudo apt install colmap; others: "
                     "https://colmap.github.io/install.html), or give its path with --colmap PATH "
                     "or the CANDI_COLMAP environment variable.");
  }
  const std::string help = TailOfFile(log_path, 5);
  std::ifstream in(log_path);
  std::stringstream text;
  text << in.rdbuf();
  try {
    return ParseColmapVersion(text.str());
  } catch (const std::invalid_argument&) {
    throw InputError(colmap, "", "does not look like COLMAP: `" + colmap + " help` exited with " +
                                     std::to_string(code) + " and printed:\n" + help);
  }
}

// The priors by image name: a prior named by the file alone ("s1_0001.jpg") also names the image in
// its session's folder ("s1/s1_0001.jpg").
std::map<std::string, Eigen::Vector3d> PriorsByImage(const std::string& path, const std::vector<DatabaseImage>& images) {
  std::map<std::string, Eigen::Vector3d> by_image;
  if (path.empty()) return by_image;
  const std::map<std::string, Eigen::Vector3d> priors = ReadPositionPriors(path);
  for (const DatabaseImage& image : images) {
    auto it = priors.find(image.name);
    if (it == priors.end()) it = priors.find(fs::path(image.name).filename().string());
    if (it != priors.end()) by_image[image.name] = it->second;
  }
  return by_image;
}

// candi's matching stage: the pairs pair_selection.h chooses, matched exactly from the database's
// descriptors into WORKSPACE/matches.txt; a summary in its log.
double MatchFeatures(const SfmOptions& options, const std::string& workspace, SfmSummary* summary,
                     const std::string& log_path, int index, int count, const SfmProgress& progress) {
  if (progress) progress(kMatchStage, index, count, 0.0, false);
  const auto start = std::chrono::steady_clock::now();
  std::vector<DatabaseImage> images = ReadColmapDescriptors(Path(workspace, "database.db"));
  std::sort(images.begin(), images.end(),
            [](const DatabaseImage& a, const DatabaseImage& b) { return a.name < b.name; });
  const size_t cleared = ClearBorderDescriptors(&images);
  const PairSelection selection = SelectPairs(images, PriorsByImage(options.priors, images), options.pairs);
  const auto& pairs = selection.pairs;
  summary->matcher = selection.strategy;
  summary->pairs_tried = pairs.size();
  double next_beat = kHeartbeatSeconds;
  const MatchListSummary matched = WriteMatchList(
      images, pairs, SiftMatchOptions{}, options.threads, Path(workspace, kMatchList), [&](size_t, size_t) {
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (progress && seconds >= next_beat) {
          progress(kMatchStage, index, count, seconds, false);
          next_beat += kHeartbeatSeconds;
        }
      });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  WriteFileAtomic(log_path, "candi's exact SIFT matcher (" + selection.strategy +
                                "; brute force, COLMAP's ratio 0.8, distance 0.7, cross-check)\n" +
                                std::to_string(images.size()) + " images, " + std::to_string(matched.pairs) +
                                " pairs, " + std::to_string(matched.pairs_written) + " with matches, " +
                                std::to_string(matched.matches) + " matches; " + std::to_string(cleared) +
                                " features in the outermost pixel row or column left out (their descriptors "
                                "differ from run to run)\n");
  if (progress) progress(kMatchStage, index, count, seconds, true);
  return seconds;
}

// The mapping stage in chunks: one mapper a chunk (its image list), `parallel` at once, then the
// chunks tied on the targets and merged into WORKSPACE/sparse/merged.
double MapInChunks(const SfmOptions& options, const SfmStage& mapper, const std::string& workspace, int index,
                   int count, const SfmProgress& progress, SfmSummary* summary) {
  const auto start = std::chrono::steady_clock::now();
  const std::map<std::string, std::vector<std::string>> chunks = ChunksByFolder(summary->images);
  fs::create_directories(Path(workspace, "chunks"));
  std::vector<std::string> names;
  for (const auto& [name, images] : chunks) {
    std::string list;
    for (const std::string& image : images) list += image + "\n";
    WriteFileAtomic(Path(workspace, "chunks/" + name + ".txt"), list);
    fs::create_directories(Path(workspace, "sparse_chunks/" + name));
    names.push_back(name);
  }
  if (progress) progress("mapper (" + std::to_string(names.size()) + " chunks)", index, count, 0.0, false);
  std::vector<std::string> errors(names.size());
  std::atomic<size_t> next{0};
  std::vector<std::thread> workers;
  for (int w = 0; w < std::min<int>(options.chunks.parallel, static_cast<int>(names.size())); ++w) {
    workers.emplace_back([&] {
      for (size_t k = next++; k < names.size(); k = next++) {
        std::vector<std::string> argv = mapper.argv;
        const auto out = std::find(argv.begin(), argv.end(), std::string("--output_path"));
        *(out + 1) = Path(workspace, "sparse_chunks/" + names[k]);
        argv.insert(argv.end(), {"--image_list_path", Path(workspace, "chunks/" + names[k] + ".txt")});
        const std::string log = Path(workspace, "logs/mapper_" + names[k] + ".log");
        try {
          WriteFileAtomic(log, "$ " + ArgvText(argv) + "\n");
          const int code = RunLogged(argv, log);
          if (code != 0 && code > 128) errors[k] = "colmap mapper (chunk " + names[k] + ") was killed; see " + log;
        } catch (const std::exception& e) {
          errors[k] = e.what();
        }
      }
    });
  }
  for (std::thread& t : workers) t.join();
  for (const std::string& e : errors)
    if (!e.empty()) throw InputError(e);
  std::map<std::string, std::string> models;
  for (const std::string& name : names) {
    ColmapModel model;
    models[name] = LargestModel(Path(workspace, "sparse_chunks/" + name), &model);
  }
  summary->chunked = TieChunks(models, chunks, options.chunks, Path(workspace, "sparse/merged"));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (progress) progress("mapper (" + std::to_string(names.size()) + " chunks)", index, count, seconds, true);
  return seconds;
}

}  // namespace

SfmSummary RunSfm(const SfmOptions& options, const std::string& images_dir,
                  const std::string& workspace_in, const SfmProgress& progress) {
  options.Check();
  SfmSummary summary;
  summary.images = ListImages(images_dir, &summary.ignored);
  if (!summary.ignored.empty()) {
    LogWarning(std::to_string(summary.ignored.size()) + " non-image file(s) in " + images_dir +
               " ignored (e.g. " + summary.ignored.front() + ")");
  }
  if (summary.images.empty()) {
    throw InputError(images_dir, "", "no images (.jpg .jpeg .png .tif .tiff .bmp .pgm .ppm .pnm) in "
                                     "the folder" + std::string(summary.ignored.empty() ? "" : "; only "
                                     "other files"));
  }
  if (summary.images.size() == 1) {
    throw InputError(images_dir, "", "only one image (" + summary.images.front() +
                                         "): structure from motion needs at least 2 overlapping photos");
  }
  if (!options.priors.empty()) ReadPositionPriors(options.priors);  // its errors before any work
  const std::string workspace = fs::absolute(workspace_in).lexically_normal().string();
  PrepareWorkspace(options, workspace, images_dir);
  fs::create_directories(Path(workspace, "logs"));
  summary.colmap = DetectColmap(options.colmap, Path(workspace, "logs/colmap_help.log"));
  LinkImages(images_dir, summary.images, workspace);
  fs::create_directories(Path(workspace, "sparse"));
  std::vector<SfmStage> stages = BuildSfmStages(options, workspace, summary.colmap.cuda);
  const int count = static_cast<int>(stages.size());
  ColmapModel model;
  for (int i = 0; i < count; ++i) {
    SfmStage& stage = stages[i];
    const std::string log_path = Path(workspace, "logs/" + stage.name + ".log");
    if (stage.name == "image_undistorter") {
      std::replace(stage.argv.begin(), stage.argv.end(), std::string(kModelPlaceholder), summary.model_dir);
    }
    const bool chunked = stage.name == "mapper" && !options.chunks.targets.empty();
    try {
      const double seconds = stage.argv.empty()
                                 ? MatchFeatures(options, workspace, &summary, log_path, i + 1, count, progress)
                             : chunked ? MapInChunks(options, stage, workspace, i + 1, count, progress, &summary)
                                       : RunSfmStage(stage, log_path, i + 1, count, progress);
      summary.stage_seconds.emplace_back(stage.name, seconds);
    } catch (const InputError& e) {
      // A mapper that ended by itself without a model found no overlap; a killed one is reported as such.
      if (stage.name != "mapper" || std::string(e.what()).find("killed by signal") != std::string::npos ||
          !LargestModel(Path(workspace, "sparse"), &model).empty()) {
        throw;
      }
      throw InputError(log_path, "", "no model: the images may not overlap (COLMAP's mapper could "
                                     "not register any pair of them); the end of its log:\n" +
                                         TailOfFile(log_path, kLogTailLines));
    }
    if (stage.name == "feature_extractor") {
      CheckExtraction(log_path, images_dir, &summary);
      // COLMAP numbers the images in the order its threads finish; the mapper follows the ids.
      RenumberImagesByName(Path(workspace, "database.db"));
    }
    if (stage.name == "matches_importer") summary.pairs_verified = CountVerifiedPairs(Path(workspace, "database.db"));
    if (chunked) {
      summary.model_dir = summary.chunked.merged_dir;
      model = ReadColmapModel(summary.model_dir);
      Summarize(model, &summary);
    } else if (stage.name == "mapper") {
      summary.model_dir = LargestModel(Path(workspace, "sparse"), &model);
      if (summary.model_dir.empty() || model.images.size() < 2) {
        throw InputError(log_path, "", "no model: the images may not overlap (COLMAP's mapper "
                                       "registered fewer than 2 images)");
      }
      Summarize(model, &summary);
    }
  }
  summary.dense_dir = Path(workspace, "dense");
  return summary;
}

}  // namespace candi::photogrammetry

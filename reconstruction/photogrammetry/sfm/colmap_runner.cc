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
#include <mutex>
#include <regex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/interrupt.h"
#include "core/log.h"
#include "core/sha256.h"
#include "reconstruction/photogrammetry/sfm/colmap_database.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"
#include "reconstruction/photogrammetry/sfm/sift_matching.h"
#include "reconstruction/photogrammetry/sfm/stage_record.h"

extern char** environ;

namespace candi::photogrammetry {

namespace fs = std::filesystem;

namespace {

constexpr const char* kModelPlaceholder = "<model>";
constexpr const char* kMatchList = "matches.txt";
constexpr double kHeartbeatSeconds = 10.0;
// What a run has finished, for --resume: "input ..." lines (what the outputs depend on), then a
// "stage <name> <seconds> [<what it found>]" line a finished stage and "chunk <name>" a mapped
// chunk. Written (atomically) after each.
constexpr const char* kStageRecord = "sfm_stages.txt";
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
  for (const char* entry : {"database.db", kMatchList, kTransitiveFolder, "images", "sparse", "dense", "logs", "sfm_report.json", "chunks",
                            "sparse_chunks", kStageRecord}) {
    if (fs::exists(fs::symlink_status(Path(workspace, entry)))) previous.push_back(entry);
  }
  if (previous.empty()) return;
  if (options.resume && fs::exists(Path(workspace, kStageRecord))) {
    fs::remove_all(Path(workspace, "images"), ec);  // links only, made again
    return;
  }
  if (!options.overwrite) {
    std::string list;
    for (const std::string& p : previous) list += (list.empty() ? "" : ", ") + p;
    throw InputError(workspace, "", "holds a previous run (" + list + ")" +
                                        (options.resume ? " without candi's record of its stages (" +
                                                              std::string(kStageRecord) + ")" : "") +
                                        "; pass --overwrite to replace it" +
                                        (options.resume ? "" : ", --resume to continue it") +
                                        ", or choose another folder");
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
  CANDI_CHECK_OPTION(!(resume && overwrite), resume, "not with overwrite (resume keeps what overwrite removes)");
  CANDI_CHECK_OPTION(pairs.strategy != PairStrategy::kPositional || !priors.empty(), priors,
                     "a priors file: positional matching pairs photos by their prior positions");
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

namespace {
// COLMAP's geometric verification of a raw match list (one thread, in the list's order).
std::vector<std::string> VerifyArgv(const SfmOptions& options, const std::string& workspace,
                                    const std::string& match_list) {
  return {options.colmap, "matches_importer", "--database_path", Path(workspace, "database.db"), "--match_list_path",
          match_list, "--match_type", "raw", "--SiftMatching.use_gpu", "0", "--SiftMatching.num_threads", "1",
          "--random_seed", "0"};
}
}  // namespace

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
  stages.push_back({"matches_importer", VerifyArgv(options, workspace, Path(workspace, kMatchList))});
  stages.push_back({kTransitiveStage, {}});
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
    if (line.find("ERROR: Single camera specified, but images have different dimensions") != std::string::npos) {
      summary->other_size.push_back(name);
      continue;
    }
    const size_t focal_at = line.find("Focal Length:");
    if (focal_at == std::string::npos) continue;
    double focal = 0;
    std::istringstream(line.substr(focal_at + 13)) >> focal;
    if (line.find("(Prior)") != std::string::npos) {
      summary->focal_priors.emplace_back(name, focal);
    } else {
      summary->no_exif.push_back(name);
      summary->default_focal_px = focal;
    }
  }
  // The extractor's threads log the photos in the order they finish: sorted, the lists are the
  // same bytes on every run.
  std::sort(summary->no_exif.begin(), summary->no_exif.end());
  std::sort(summary->unreadable.begin(), summary->unreadable.end());
  std::sort(summary->other_size.begin(), summary->other_size.end());
  std::sort(summary->focal_priors.begin(), summary->focal_priors.end());
}

std::vector<std::vector<std::string>> IdenticalFiles(const std::string& dir, const std::vector<std::string>& names) {
  // Only files of one size can be the same; only those are read.
  std::map<uintmax_t, std::vector<std::string>> by_size;
  for (const std::string& name : names) by_size[fs::file_size(fs::path(dir) / name)].push_back(name);
  std::vector<std::vector<std::string>> groups;
  for (const auto& [size, same_size] : by_size) {
    if (same_size.size() < 2) continue;
    std::map<std::string, std::vector<std::string>> by_hash;
    for (const std::string& name : same_size) by_hash[Sha256OfFile((fs::path(dir) / name).string())].push_back(name);
    for (auto& [hash, group] : by_hash) {
      if (group.size() < 2) continue;
      std::sort(group.begin(), group.end());
      groups.push_back(group);
    }
  }
  std::sort(groups.begin(), groups.end());
  return groups;
}

double FractionInLog(const std::string& text, size_t images) {
  static const std::regex counted(R"(\[(\d+)/(\d+)\])"), registering(R"(Registering image #\d+ \((\d+)\))");
  double fraction = -1;
  std::ptrdiff_t at = -1;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), counted); it != std::sregex_iterator(); ++it) {
    const double n = std::stod((*it)[2].str());
    if (n > 0) fraction = std::stod((*it)[1].str()) / n, at = it->position();
  }
  if (images > 0) {
    for (auto it = std::sregex_iterator(text.begin(), text.end(), registering); it != std::sregex_iterator(); ++it) {
      if (it->position() > at) fraction = std::stod((*it)[1].str()) / static_cast<double>(images), at = it->position();
    }
  }
  return fraction < 0 ? -1.0 : std::min(fraction, 1.0);
}

namespace {
// The last few kB of a log, where the newest counter is.
std::string EndOfLog(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "";
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  const std::streamoff from = std::max<std::streamoff>(0, size - 4096);
  in.seekg(from);
  std::string text(static_cast<size_t>(size - from), '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  return text;
}
}  // namespace

double RunSfmStage(const SfmStage& stage, const std::string& log_path, int index, int count,
                   const SfmProgress& progress, size_t images) {
  if (progress) progress(stage.name, index, count, 0.0, false, 0.0);
  WriteFileAtomic(log_path, "$ " + ArgvText(stage.argv) + "\n");
  const auto start = std::chrono::steady_clock::now();
  const int code = RunLogged(stage.argv, log_path, [&](double seconds) {
    if (progress) progress(stage.name, index, count, seconds, false, FractionInLog(EndOfLog(log_path), images));
  });
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (code != 0) {
    const std::string how = code > 128 ? "was killed by signal " + std::to_string(code - 128)
                                       : "failed with exit code " + std::to_string(code);
    throw InputError(log_path, "", "colmap " + stage.name + " " + how + "; the end of its log:\n" +
                                       TailOfFile(log_path, kLogTailLines));
  }
  if (progress) progress(stage.name, index, count, seconds, true, 1.0);
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

std::string ListText(const std::vector<std::string>& names, size_t most = 10) {
  std::string list;
  for (size_t k = 0; k < names.size() && k < most; ++k) list += (k == 0 ? "" : ", ") + names[k];
  if (names.size() > most) list += ", ... (" + std::to_string(names.size()) + " in all)";
  return list;
}

// After feature extraction: photos COLMAP could not decode, and photos of another size than the
// first when one camera is shared, are skipped (a warning each), unless fewer than two remain;
// EXIF focal lengths that differ under one shared camera are warned of.
void CheckExtraction(const std::string& log_path, const std::string& images_dir, bool single_camera,
                     SfmSummary* summary) {
  ParseFeatureExtractionLog(log_path, summary);
  const size_t skipped = summary->unreadable.size() + summary->other_size.size();
  if (summary->images.size() - skipped < 2) {
    throw InputError(images_dir, "", "COLMAP could not use " + std::to_string(skipped) + " of the " +
                                         std::to_string(summary->images.size()) + " images (" +
                                         ListText(summary->unreadable.empty() ? summary->other_size
                                                                              : summary->unreadable) +
                                         (summary->unreadable.empty() ? "): other sizes than the first with one "
                                                                        "camera shared (--camera-per-image)"
                                                                      : "): corrupt or not images") +
                                         "; fewer than 2 usable photos remain (see " + log_path + ")");
  }
  if (!summary->unreadable.empty()) LogWarning("COLMAP could not read (skipped): " + ListText(summary->unreadable));
  if (!summary->other_size.empty()) {
    LogWarning(std::to_string(summary->other_size.size()) + " photo(s) skipped: their size differs from the first "
               "photo's and one camera is shared (--camera-per-image gives each photo its own): " +
               ListText(summary->other_size));
  }
  if (single_camera && !summary->focal_priors.empty()) {
    const auto [lo, hi] = std::minmax_element(summary->focal_priors.begin(), summary->focal_priors.end(),
                                              [](const auto& a, const auto& b) { return a.second < b.second; });
    if (hi->second > 1.01 * lo->second) {
      LogWarning("the photos' EXIF focal lengths differ (" + lo->first + ": " + std::to_string(lo->second) + " px, " +
                 hi->first + ": " + std::to_string(hi->second) + " px) but one camera is shared: photos of several "
                 "cameras or zoom settings want --camera-per-image");
    }
  }
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

// The database's images in name order, their unstable border descriptors cleared (`cleared` of
// them; sift_matching.h).
std::vector<DatabaseImage> ImagesToMatch(const std::string& workspace, size_t* cleared) {
  std::vector<DatabaseImage> images = ReadColmapDescriptors(Path(workspace, "database.db"));
  std::sort(images.begin(), images.end(),
            [](const DatabaseImage& a, const DatabaseImage& b) { return a.name < b.name; });
  *cleared = ClearBorderDescriptors(&images);
  return images;
}

// candi's matching stage: the pairs pair_selection.h chooses, matched exactly from the database's
// descriptors into WORKSPACE/matches.txt; a summary in its log.
double MatchFeatures(const SfmOptions& options, const std::string& workspace, SfmSummary* summary,
                     const std::string& log_path, int index, int count, const SfmProgress& progress) {
  if (progress) progress(kMatchStage, index, count, 0.0, false, 0.0);
  const auto start = std::chrono::steady_clock::now();
  size_t cleared = 0;
  const std::vector<DatabaseImage> images = ImagesToMatch(workspace, &cleared);
  const std::map<std::string, Eigen::Vector3d> positions = PriorsByImage(options.priors, images);
  if (!options.priors.empty() && positions.empty()) {
    throw InputError(options.priors, "", "names none of the " + std::to_string(images.size()) +
                                             " photos (e.g. " + images.front().name + ")");
  }
  const PairSelection selection = SelectPairs(images, positions, options.pairs);
  const auto& pairs = selection.pairs;
  summary->matcher = selection.strategy;
  summary->pairs_tried = pairs.size();
  double next_beat = kHeartbeatSeconds;
  const MatchListSummary matched = WriteMatchList(
      images, pairs, SiftMatchOptions{}, options.threads, Path(workspace, kMatchList), [&](size_t done, size_t total) {
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (progress && seconds >= next_beat) {
          progress(kMatchStage, index, count, seconds, false, total == 0 ? -1.0 : double(done) / double(total));
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
  if (progress) progress(kMatchStage, index, count, seconds, true, 1.0);
  return seconds;
}

// candi's transitive matching stage (kTransitiveStage): `transitive_rounds` rounds, each matching
// the pairs TransitivePairs proposes from the pairs verified so far and never tried, then having
// COLMAP verify them. A summary in its log; what it added in `summary`.
double MatchTransitively(const SfmOptions& options, const std::string& workspace, SfmSummary* summary,
                         const std::string& log_path, int index, int count, const SfmProgress& progress) {
  if (progress) progress(kTransitiveStage, index, count, 0.0, false, 0.0);
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  const PairSelectionOptions& p = options.pairs;
  std::string log = "candi's transitive matching (" + std::to_string(p.transitive_rounds) + " rounds, " +
                    std::to_string(p.transitive_neighbours) + " new pairs a photo a round at most)\n";
  if (p.transitive_rounds == 0 || summary->matcher == "exhaustive") {
    log += p.transitive_rounds == 0 ? "no rounds asked for\n" : "nothing to add: every pair was matched\n";
  } else {
    size_t cleared = 0;
    const std::vector<DatabaseImage> images = ImagesToMatch(workspace, &cleared);
    std::map<std::string, size_t> index_of;
    for (size_t i = 0; i < images.size(); ++i) index_of[images[i].name] = i;
    const auto indices = [&](const std::set<std::pair<std::string, std::string>>& names) {
      std::vector<std::pair<size_t, size_t>> pairs;
      for (const auto& [a, b] : names) {
        const auto ia = index_of.find(a), ib = index_of.find(b);
        if (ia != index_of.end() && ib != index_of.end() && ia->second != ib->second)
          pairs.push_back({std::min(ia->second, ib->second), std::max(ia->second, ib->second)});
      }
      return pairs;
    };
    const std::string database = Path(workspace, "database.db");
    const std::vector<std::pair<size_t, size_t>> matched = indices(MatchedPairNames(database));
    std::set<std::pair<size_t, size_t>> tried(matched.begin(), matched.end());
    fs::create_directories(Path(workspace, kTransitiveFolder));
    size_t added = 0;
    double next_beat = kHeartbeatSeconds;
    for (int round = 1; round <= p.transitive_rounds; ++round) {
      const auto pairs =
          TransitivePairs(images.size(), indices(VerifiedPairNames(database)), tried, p.transitive_neighbours);
      const size_t before = CountVerifiedPairs(database);
      log += "round " + std::to_string(round) + ": " + std::to_string(pairs.size()) + " pairs";
      if (pairs.empty()) {
        log += "\n";
        break;
      }
      tried.insert(pairs.begin(), pairs.end());
      added += pairs.size();
      const std::string list = Path(workspace, std::string(kTransitiveFolder) + "/round_" + std::to_string(round) + ".txt");
      const MatchListSummary written = WriteMatchList(
          images, pairs, SiftMatchOptions{}, options.threads, list, [&](size_t done, size_t total) {
            if (progress && elapsed() >= next_beat) {
              progress(kTransitiveStage, index, count, elapsed(), false,
                       (round - 1 + 0.9 * double(done) / double(std::max<size_t>(total, 1))) / p.transitive_rounds);
              next_beat += kHeartbeatSeconds;
            }
          });
      if (written.pairs_written > 0) {
        // COLMAP's heartbeats, as this stage's (its pairs' share, 0.9 of the round, is done).
        const SfmProgress verifying = [&](const std::string&, int, int, double, bool, double fraction) {
          if (progress) {
            progress(kTransitiveStage, index, count, elapsed(), false,
                     (round - 1 + 0.9 + 0.1 * std::max(0.0, fraction)) / p.transitive_rounds);
          }
        };
        RunSfmStage({"matches_importer", VerifyArgv(options, workspace, list)},
                    Path(workspace, "logs/" + std::string(kTransitiveStage) + "_" + std::to_string(round) + ".log"),
                    index, count, verifying, images.size());
      }
      log += ", " + std::to_string(written.pairs_written) + " with matches, " +
             std::to_string(CountVerifiedPairs(database) - before) + " verified\n";
      if (progress) progress(kTransitiveStage, index, count, elapsed(), false, double(round) / p.transitive_rounds);
    }
    summary->pairs_tried += added;
    summary->matcher += " + transitive " + std::to_string(p.transitive_rounds) + " x " +
                        std::to_string(p.transitive_neighbours);
  }
  const double seconds = elapsed();
  WriteFileAtomic(log_path, log);
  if (progress) progress(kTransitiveStage, index, count, seconds, true, 1.0);
  return seconds;
}

// The mapping stage in chunks: one mapper a chunk (its image list), run by `run_mappers` (nullptr:
// `options.chunks.parallel` at once in this process), then the chunks tied on the targets and
// merged into WORKSPACE/sparse/merged.
double MapInChunks(const SfmOptions& options, const SfmStage& mapper, const std::string& workspace, int index,
                   int count, const SfmProgress& progress, const ChunkMapperRunner& run_mappers,
                   StageRecord* record, SfmSummary* summary) {
  const auto start = std::chrono::steady_clock::now();
  const std::map<std::string, std::vector<std::string>> chunks = ChunksByFolder(summary->images);
  fs::create_directories(Path(workspace, "chunks"));
  std::vector<ChunkMapperJob> jobs;
  for (const auto& [name, images] : chunks) {
    if (images.size() < 2) continue;  // nothing to map: reported below
    if (record->chunks.count(name)) continue;  // mapped by the run this one resumes
    std::error_code ec;
    fs::remove_all(Path(workspace, "sparse_chunks/" + name), ec);  // what an interrupted mapper left
    std::string list;
    for (const std::string& image : images) list += image + "\n";
    WriteFileAtomic(Path(workspace, "chunks/" + name + ".txt"), list);
    fs::create_directories(Path(workspace, "sparse_chunks/" + name));
    ChunkMapperJob job;
    job.chunk = name;
    job.argv = mapper.argv;
    const auto out = std::find(job.argv.begin(), job.argv.end(), std::string("--output_path"));
    *(out + 1) = Path(workspace, "sparse_chunks/" + name);
    job.argv.insert(job.argv.end(), {"--image_list_path", Path(workspace, "chunks/" + name + ".txt")});
    job.log = Path(workspace, "logs/mapper_" + name + ".log");
    jobs.push_back(std::move(job));
  }
  const std::string stage = "mapper (" + std::to_string(jobs.size()) + " chunks)";
  if (progress) progress(stage, index, count, 0.0, false, 0.0);
  const auto chunk_done = [&](size_t job, size_t finished) {
    record->chunks.insert(jobs[job].chunk);  // a mapper that found no model is done too
    record->Write();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (progress && finished < jobs.size()) progress(stage, index, count, seconds, false, double(finished) / jobs.size());
  };
  const std::vector<std::string> errors =
      jobs.empty() ? std::vector<std::string>()
      : run_mappers ? run_mappers(jobs)
                    : RunChunkMappers(jobs, options.chunks.parallel, nullptr, "", chunk_done);
  CANDI_CHECK_EQ(errors.size(), jobs.size());
  for (size_t k = 0; k < jobs.size(); ++k)
    if (errors[k].empty()) record->chunks.insert(jobs[k].chunk);
  record->Write();
  for (const std::string& e : errors)
    if (!e.empty()) throw InputError(e);
  std::map<std::string, std::string> models;
  for (const auto& [name, images] : chunks) {
    ColmapModel model;
    models[name] = images.size() < 2 ? "" : LargestModel(Path(workspace, "sparse_chunks/" + name), &model);
  }
  std::error_code ec;
  fs::remove_all(Path(workspace, "sparse/merged"), ec);
  // The verified matches between two chunks' photos join their points in the joint adjustment.
  const std::vector<PairMatches> across =
      options.chunks.joint.enabled
          ? ReadVerifiedMatches(Path(workspace, "database.db"),
                                [](const std::string& a, const std::string& b) { return ChunkOfName(a) != ChunkOfName(b); })
          : std::vector<PairMatches>();
  ChunkedMappingOptions tie = options.chunks;
  tie.joint.one_camera = options.single_camera;  // every chunk holds a copy of the one camera
  summary->chunked = TieChunks(models, chunks, across, tie, Path(workspace, "sparse/merged"));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (progress) progress(stage, index, count, seconds, true, 1.0);
  return seconds;
}

}  // namespace

std::vector<std::string> RunChunkMappers(const std::vector<ChunkMapperJob>& jobs, int parallel,
                                         const std::function<bool(size_t)>& mine, const std::string& by,
                                         const std::function<void(size_t, size_t)>& finished) {
  CANDI_CHECK(parallel >= 1);
  std::vector<size_t> todo;
  for (size_t k = 0; k < jobs.size(); ++k)
    if (!mine || mine(k)) todo.push_back(k);
  std::vector<std::string> errors(jobs.size());
  std::atomic<size_t> next{0};
  std::mutex finished_mutex;
  size_t finished_count = 0;
  std::vector<std::thread> workers;
  for (int w = 0; w < std::min<int>(parallel, static_cast<int>(todo.size())); ++w) {
    workers.emplace_back([&] {
      for (size_t t = next++; t < todo.size(); t = next++) {
        const ChunkMapperJob& job = jobs[todo[t]];
        std::string& error = errors[todo[t]];
        try {
          WriteFileAtomic(job.log, (by.empty() ? "" : "# " + by + "\n") + "$ " + ArgvText(job.argv) + "\n");
          const int code = RunLogged(job.argv, job.log);
          // COLMAP's mapper exits 1 when it finds no model: that chunk is left untied, named.
          if (code > 128) error = "colmap mapper (chunk " + job.chunk + ") was killed; see " + job.log;
        } catch (const std::exception& e) {
          error = e.what();
        }
        if (finished) {
          const std::lock_guard<std::mutex> lock(finished_mutex);
          finished(todo[t], ++finished_count);
        }
      }
    });
  }
  for (std::thread& t : workers) t.join();
  return errors;
}

SfmSummary RunSfm(const SfmOptions& options, const std::string& images_dir,
                  const std::string& workspace_in, const SfmProgress& progress,
                  const ChunkMapperRunner& run_mappers) {
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
  for (const std::vector<std::string>& group : IdenticalFiles(images_dir, summary.images)) {
    // The same photo twice gives a pair with no baseline: the first name is kept.
    for (size_t k = 1; k < group.size(); ++k) summary.duplicates.emplace_back(group[k], group[0]);
  }
  if (!summary.duplicates.empty()) {
    std::vector<std::string> dropped;
    for (const auto& [copy, kept] : summary.duplicates) dropped.push_back(copy + " (= " + kept + ")");
    LogWarning(std::to_string(dropped.size()) + " photo(s) are byte-for-byte copies of another and are left out: " +
               ListText(dropped));
    for (const auto& [copy, kept] : summary.duplicates)
      summary.images.erase(std::find(summary.images.begin(), summary.images.end(), copy));
    if (summary.images.size() < 2) {
      throw InputError(images_dir, "", "only one distinct photo (" + summary.images.front() +
                                           "; the others are copies of it): structure from motion needs at "
                                           "least 2 overlapping photos");
    }
  }
  if (!options.priors.empty()) ReadPositionPriors(options.priors);  // its errors before any work
  const std::string workspace = fs::absolute(workspace_in).lexically_normal().string();
  PrepareWorkspace(options, workspace, images_dir);
  StageRecord record;
  const std::vector<std::string> inputs = StageInputs(options, summary.images);
  if (options.resume && fs::exists(Path(workspace, kStageRecord))) {
    record = StageRecord::Read(Path(workspace, kStageRecord));
    const auto differ = std::mismatch(inputs.begin(), inputs.end(), record.inputs.begin(), record.inputs.end());
    if (differ.first != inputs.end() || differ.second != record.inputs.end()) {
      const std::string now = differ.first == inputs.end() ? "(none)" : *differ.first;
      const std::string then = differ.second == record.inputs.end() ? "(none)" : *differ.second;
      throw InputError(Path(workspace, kStageRecord), "", "the run to resume had other inputs (" + then +
                                                              ", now " + now + "); --overwrite starts again");
    }
  }
  record.path = Path(workspace, kStageRecord);
  record.inputs = inputs;
  record.Write();
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
    // A stage the resumed run finished is not run again (chunked mapping: the chunks it mapped);
    // one it left unfinished starts again from nothing.
    const auto finished = record.stages.find(stage.name);
    const bool skip = finished != record.stages.end();
    if (skip) {
      if (progress) progress(stage.name + " (finished before)", i + 1, count, finished->second.first, true, 1.0);
      summary.stage_seconds.emplace_back(stage.name, finished->second.first);
    } else {
      ClearUnfinishedStage(stage.name, workspace);
    }
    try {
      if (!skip) {
        const double seconds =
            stage.name == kMatchStage ? MatchFeatures(options, workspace, &summary, log_path, i + 1, count, progress)
            : stage.name == kTransitiveStage
                ? MatchTransitively(options, workspace, &summary, log_path, i + 1, count, progress)
            : chunked ? MapInChunks(options, stage, workspace, i + 1, count, progress, run_mappers, &record, &summary)
                      : RunSfmStage(stage, log_path, i + 1, count, progress, summary.images.size());
        summary.stage_seconds.emplace_back(stage.name, seconds);
      }
    } catch (const InputError& e) {
      // A mapper that ended by itself without a model found no overlap; a killed one is reported as such.
      if (stage.name != "mapper" || chunked || std::string(e.what()).find("killed by signal") != std::string::npos ||
          !LargestModel(Path(workspace, "sparse"), &model).empty()) {
        throw;
      }
      throw InputError(log_path, "", "no model: the images may not overlap (COLMAP's mapper could "
                                     "not register any pair of them); the end of its log:\n" +
                                         TailOfFile(log_path, kLogTailLines));
    }
    if (stage.name == "feature_extractor") {
      CheckExtraction(log_path, images_dir, options.single_camera, &summary);
      // COLMAP numbers the images in the order its threads finish; the mapper follows the ids.
      if (!skip) RenumberImagesByName(Path(workspace, "database.db"));
    }
    // The matching stages record the pairs tried so far and how they were chosen.
    const bool matching = stage.name == kMatchStage || stage.name == kTransitiveStage;
    if (matching && skip) {
      std::istringstream found(finished->second.second);  // "<pairs> <how they were chosen, spaces and all>"
      found >> summary.pairs_tried;
      std::getline(found >> std::ws, summary.matcher);
    }
    if (stage.name == "matches_importer" || stage.name == kTransitiveStage) {
      summary.pairs_verified = CountVerifiedPairs(Path(workspace, "database.db"));
    }
    if (!skip && !chunked) {
      record.stages[stage.name] = {summary.stage_seconds.back().second,
                                   matching ? std::to_string(summary.pairs_tried) + " " + summary.matcher : ""};
      record.Write();
    }
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

// Issue 9's fault injection: the failures a long job meets in the field, each on the real
// executable. Every one must leave the outputs that existed before it intact (old or complete
// new, never half-written, no temporary left behind), say what happened, and exit non-zero:
//   - a read error mid-file (a preloaded library, tests/fault/fault_inject.c, fails read()/pread()
//     of one file past a byte offset with EIO);
//   - a full disk (a 1 MiB tmpfs, when the tests may mount one: root) and a file-size limit
//     (RLIMIT_FSIZE, any user; writes fail with EFBIG the way they do with ENOSPC);
//   - COLMAP killed (SIGKILL) in the middle of a stage of `candi sfm`;
//   - SIGINT during `candi build`, then `candi build --resume` finishing the same archive;
//   - LAZ and COPC writes on a full disk, into a folder that refuses files, and interrupted;
//   - the old copy a replaced archive or republished site leaves that cannot be removed (the
//     preloaded library fails unlink()/rmdir() of paths holding a text with EBUSY): named.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "io/image/png_io.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/scenes/synthetic_views.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi::testing {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// candi started in the background, its stdout and stderr going to files.
class Process {
 public:
  // `setup` runs in the child between fork and exec (only async-signal-safe calls).
  Process(const std::vector<std::string>& args, const std::string& log_dir,
          const std::vector<std::string>& extra_env = {}, void (*setup)() = nullptr)
      : out_(log_dir + "/stdout.txt"), err_(log_dir + "/stderr.txt") {
    std::vector<std::string> argv = {CANDI_EXECUTABLE};
    argv.insert(argv.end(), args.begin(), args.end());
    std::vector<char*> cargv;
    for (std::string& a : argv) cargv.push_back(a.data());
    cargv.push_back(nullptr);
    std::vector<std::string> env(extra_env);
    for (char** e = environ; *e != nullptr; ++e) env.push_back(*e);
    std::vector<char*> cenv;
    for (std::string& e : env) cenv.push_back(e.data());
    cenv.push_back(nullptr);
    pid_ = fork();
    if (pid_ == 0) {
      const int out = open(out_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      const int err = open(err_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(out, 1);
      dup2(err, 2);
      if (setup != nullptr) setup();
      execve(cargv[0], cargv.data(), cenv.data());
      _exit(127);
    }
  }
  ~Process() {
    if (pid_ > 0 && !waited_) {
      kill(pid_, SIGKILL);
      Wait();
    }
  }
  pid_t pid() const { return pid_; }
  bool Running() const {
    if (pid_ <= 0 || waited_) return false;
    siginfo_t info{};
    return waitid(P_PID, pid_, &info, WEXITED | WNOHANG | WNOWAIT) == 0 && info.si_pid == 0;
  }
  int Wait() {  // the raw wait status
    waitpid(pid_, &status_, 0);
    waited_ = true;
    return status_;
  }
  std::string Stdout() const { return ReadBytes(out_); }
  std::string Stderr() const { return ReadBytes(err_); }

 private:
  std::string out_, err_;
  pid_t pid_ = -1;
  int status_ = 0;
  bool waited_ = false;
};

// Runs candi to completion: {exit code (or 128 + signal), stderr}.
std::pair<int, std::string> RunToEnd(const std::vector<std::string>& args, const std::string& log_dir,
                                const std::vector<std::string>& env = {}, void (*setup)() = nullptr) {
  Process p(args, log_dir, env, setup);
  const int status = p.Wait();
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  return {code, p.Stderr()};
}

// Every file under `dir` whose name holds candi's temporary marker.
std::vector<std::string> Temporaries(const std::string& dir) {
  std::vector<std::string> found;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    if (e.path().filename().string().find(".candi-tmp-") != std::string::npos) found.push_back(e.path().string());
  return found;
}

bool Contains(const std::string& text, const std::string& what) { return text.find(what) != std::string::npos; }

// A binary PLY of n coloured points (~ 15 bytes each).
void WriteCloud(const std::string& path, int n, uint32_t seed) {
  PointCloud c;
  c.schema.colors = true;
  c.SetSchema(c.schema);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 10.0f);
  for (int i = 0; i < n; ++i) {
    c.positions.emplace_back(u(rng), u(rng), 0.1 * u(rng));
    c.colors.push_back({static_cast<uint8_t>(i), 120, static_cast<uint8_t>(200 - i % 100)});
  }
  io::WritePointCloud(path, c);
}

std::string LogDir(const TempDir& dir) {
  fs::create_directories(dir.File("logs"));
  return dir.File("logs");
}

TEST(Fault, AReadErrorMidFileIsReportedAndTheOutputKept) {
  TempDir dir;
  WriteCloud(dir.File("in.ply"), 200000, 1);
  WriteBytes(dir.File("out.ply"), "an earlier output\n");
  const std::vector<std::string> env = {
      "LD_PRELOAD=" CANDI_FAULT_INJECT_LIB, "CANDI_FAULT_READ=/in.ply:1000000",
      // Under AddressSanitizer (make test-asan) the preloaded library comes before its runtime.
      std::string("ASAN_OPTIONS=verify_asan_link_order=0:") + (getenv("ASAN_OPTIONS") ? getenv("ASAN_OPTIONS") : "")};
  const auto [code, err] = RunToEnd({"convert", dir.File("in.ply"), dir.File("out.ply")}, LogDir(dir), env);
  EXPECT_EQ(code, 2) << err;
  EXPECT_TRUE(Contains(err, dir.File("in.ply"))) << err;
  EXPECT_TRUE(Contains(err, "read error: Input/output error")) << err;
  EXPECT_TRUE(Contains(err, "byte ")) << "the position is named: " << err;
  EXPECT_EQ(ReadBytes(dir.File("out.ply")), "an earlier output\n");
  EXPECT_TRUE(Temporaries(dir.path()).empty());
  // The same command without the fault succeeds: the failure was the injected one.
  const auto [ok, ok_err] = RunToEnd({"convert", dir.File("in.ply"), dir.File("out.ply")}, LogDir(dir));
  EXPECT_EQ(ok, 0) << ok_err;
  EXPECT_EQ(io::ReadPointCloud(dir.File("out.ply")).size(), 200000u);
}

// A 1 MiB tmpfs mounted on `path` (created) while it lives, where the tests may mount one (root).
struct SmallDisk {
  explicit SmallDisk(const std::string& p) : path(p) {
    fs::create_directories(path);
    mounted = mount("candi-test", path.c_str(), "tmpfs", 0, "size=1m") == 0;
    if (!mounted) why = std::string("cannot mount a small tmpfs here (") + std::strerror(errno) + "; needs root)";
  }
  ~SmallDisk() {
    if (mounted) umount2(path.c_str(), MNT_DETACH);
  }
  std::string path, why;
  bool mounted = false;
};

TEST(Fault, AFullDiskIsReportedAndTheOutputKept) {
  TempDir dir;
  WriteCloud(dir.File("in.ply"), 200000, 2);  // ~3 MB: more than the disk holds
  const SmallDisk small(dir.File("disk"));
  if (!small.mounted) GTEST_SKIP() << small.why << ": the file-size-limit test covers write failures";
  const std::string& disk = small.path;
  WriteBytes(disk + "/out.ply", "an earlier output\n");
  const auto [code, err] = RunToEnd({"convert", dir.File("in.ply"), disk + "/out.ply"}, LogDir(dir));
  EXPECT_EQ(code, 2) << err;
  EXPECT_TRUE(Contains(err, disk + "/out.ply")) << err;
  EXPECT_TRUE(Contains(err, "No space left on device")) << err;
  EXPECT_TRUE(Contains(err, "the destination is unchanged")) << err;
  EXPECT_EQ(ReadBytes(disk + "/out.ply"), "an earlier output\n");
  EXPECT_TRUE(Temporaries(disk).empty());
}

void LimitFileSize() {  // in the child: writes beyond 1 MiB fail with EFBIG instead of SIGXFSZ
  signal(SIGXFSZ, SIG_IGN);
  struct rlimit limit = {1 << 20, 1 << 20};
  setrlimit(RLIMIT_FSIZE, &limit);
}

// A scene of a point layer and a foundation layer (the bundled drawing, few points), `views` views.
json FaultScene(int views) {
  json scene = json::parse(R"({
    "candi_scene": 1, "seed": 3,
    "render": {"repeat_level": 64, "width": 320, "height": 240},
    "layers": [
      {"name": "cloud", "kind": "points", "file": "cloud.ply", "opacity": 0.5},
      {"name": "hill", "kind": "foundation", "dxf": "FOUNDATION", "sections": ["D"],
       "samples_per_side": 40, "angular_steps": 12, "count": 20000, "opacity": 0.4,
       "world_from_layer": {"scale": 0.0001, "translation": [5, 5, -3]}}]})");
  scene["layers"][1]["dxf"] = fs::absolute("examples/borobudur/foundation.dxf").string();
  scene["views"] = json::array();
  for (int v = 0; v < views; ++v) scene["views"].push_back({{"name", "v" + std::to_string(v)}});
  return scene;
}

TEST(Fault, AFileSizeLimitDuringBuildKeepsTheEarlierArchive) {
  TempDir dir;
  WriteCloud(dir.File("cloud.ply"), 20000, 3);
  WriteBytes(dir.File("scene.json"), FaultScene(1).dump());
  const auto [built, built_err] = RunToEnd({"build", dir.File("scene.json"), "-o", dir.File("out")}, LogDir(dir));
  ASSERT_EQ(built, 0) << built_err;
  const std::string manifest = ReadBytes(dir.File("out/archive.json"));
  const std::string layer = ReadBytes(dir.File("out/layers/cloud.ply"));

  WriteCloud(dir.File("cloud.ply"), 200000, 4);  // its layer file now outgrows the limit
  const auto [code, err] = RunToEnd({"build", dir.File("scene.json"), "-o", dir.File("out")}, LogDir(dir), {}, LimitFileSize);
  EXPECT_EQ(code, 2) << err;
  EXPECT_TRUE(Contains(err, "write failed: File too large")) << err;
  EXPECT_TRUE(Contains(err, "the destination is unchanged")) << err;
  EXPECT_EQ(ReadBytes(dir.File("out/archive.json")), manifest);
  EXPECT_EQ(ReadBytes(dir.File("out/layers/cloud.ply")), layer);
  EXPECT_NO_THROW(io::ReadPointCloud(dir.File("out/layers/hill.ply")));
  EXPECT_TRUE(Temporaries(dir.path()).empty());
}

// The packer writes its data files on a thread of its own while it sorts the next cell: a
// write failing there still stops the pack with the file's error, and the earlier archive stays.
TEST(Fault, AFileSizeLimitDuringPackKeepsTheEarlierArchive) {
  TempDir dir;
  WriteCloud(dir.File("cloud.ply"), 20000, 3);
  const auto [packed, packed_err] = RunToEnd({"pack", dir.File("cloud.ply"), "-o", dir.File("out.archive")}, LogDir(dir));
  ASSERT_EQ(packed, 0) << packed_err;
  const std::string manifest = ReadBytes(dir.File("out.archive/manifest.json"));

  WriteCloud(dir.File("cloud.ply"), 400000, 4);  // 3.2 MB of chunks: beyond the limit
  const auto [code, err] =
      RunToEnd({"pack", dir.File("cloud.ply"), "-o", dir.File("out.archive")}, LogDir(dir), {}, LimitFileSize);
  EXPECT_EQ(code, 2) << err;
  EXPECT_TRUE(Contains(err, "data-00000.bin")) << err;
  EXPECT_TRUE(Contains(err, "File too large")) << err;
  EXPECT_EQ(ReadBytes(dir.File("out.archive/manifest.json")), manifest);
  EXPECT_TRUE(Temporaries(dir.path()).empty());
}

// The pid of a child of `parent` whose command line holds `word`, or 0.
pid_t FindChild(pid_t parent, const std::string& word) {
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(e.path() / "stat");
    std::string line;
    if (!std::getline(stat, line)) continue;
    const size_t close = line.rfind(')');
    if (close == std::string::npos) continue;
    char state = 0;
    int ppid = 0;
    if (std::sscanf(line.c_str() + close + 1, " %c %d", &state, &ppid) != 2 || ppid != parent) continue;
    std::string cmdline = ReadBytes((e.path() / "cmdline").string());
    if (Contains(cmdline, word)) return static_cast<pid_t>(std::stol(name));
  }
  return 0;
}

// A COLMAP that stops itself (SIGSTOP) when it is started for `stage` (with an argument holding
// `argument`, when given) and is the real one otherwise: DIR/colmap-held, returned.
std::string HeldColmap(const TempDir& dir, const std::string& stage, const std::string& argument = "") {
  const std::string colmap = candi::testing::RunCommand("command -v colmap").output;
  WriteBytes(dir.File("colmap-held"), "#!/bin/sh\nif [ \"$1\" = " + stage + " ]; then case \"$*\" in *" + argument +
                                          "*) kill -STOP $$;; esac; fi\nexec " + colmap.substr(0, colmap.find('\n')) +
                                          " \"$@\"\n");
  fs::permissions(dir.File("colmap-held"), fs::perms::owner_all);
  return dir.File("colmap-held");
}

// A COLMAP stage killed: its name, the signal and its log reach the user, exit 2. The stage is
// held at its start (a wrapper stops itself with SIGSTOP before it runs the real COLMAP), so the
// kill never races the stage's end, however loaded the machine.
TEST(Fault, ColmapKilledMidStageIsReported) {
  if (!OnPath("colmap")) GTEST_SKIP() << "COLMAP is not installed (scripts/deps.sh installs it)";
  TempDir dir;
  fs::create_directories(dir.File("photos"));
  std::mt19937 rng(5);
  for (int k = 0; k < 3; ++k) {  // textured photos: features to extract, then to match
    Image8 img(320, 240, 3);
    for (int y = 0; y < 240; ++y)
      for (int x = 0; x < 320; ++x)
        for (int c = 0; c < 3; ++c) img.at(x, y, c) = static_cast<uint8_t>((((x + 7 * k) / 8 * 37 + y / 8 * 91 + c * 50) % 251) ^ (rng() & 31));
    io::WritePng(dir.File("photos/p" + std::to_string(k) + ".png"), img);
  }
  Process p({"sfm", dir.File("photos"), "-o", dir.File("ws"), "--colmap", HeldColmap(dir, "matches_importer")},
            LogDir(dir));
  pid_t victim = 0;
  while (victim == 0 && p.Running()) {  // ends: the stage waits, stopped, for this kill
    victim = FindChild(p.pid(), "matches_importer");
    if (victim == 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_NE(victim, 0) << "COLMAP's matches_importer never started: " << p.Stderr();
  kill(victim, SIGKILL);
  const int status = p.Wait();
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 2);
  const std::string err = p.Stderr();
  EXPECT_TRUE(Contains(err, "matches_importer was killed by signal 9")) << err;
  EXPECT_TRUE(Contains(err, "logs/")) << "the log is named: " << err;
  // The stages before it finished and are kept: the features in the database, candi's matches.
  EXPECT_GT(fs::file_size(dir.File("ws/database.db")), 10000u);
  EXPECT_TRUE(Contains(ReadBytes(dir.File("ws/logs/feature_extractor.log")), "Elapsed time"));
  EXPECT_GT(fs::file_size(dir.File("ws/matches.txt")), 0u);
  EXPECT_TRUE(Temporaries(dir.path()).empty());
}

// Eight synthetic photos of 400 x 300 on an 80-degree arc (as
// SfmDense.SyntheticPhotosReconstructAccuratelyAndCompletely) in `folder`.
void WriteEightSyntheticPhotos(const std::string& folder) {
  photogrammetry::SyntheticViewsOptions scene;
  scene.views = 8;
  scene.width = 400;
  scene.height = 300;
  scene.arc_degrees = 80;
  scene.supersample = 2;
  scene.texture_cell = 0.03;
  photogrammetry::WriteSyntheticImages(photogrammetry::RenderSyntheticViews(scene), folder);
}

// `candi sfm` interrupted (SIGINT) in the mapper, then `--resume`d: the finished stages are not
// run again, the mapper starts again from nothing, and the model is the same bytes as one run
// straight through. The mapper is held at its start (as above), so where the run stops is no
// matter of timing. Eight synthetic photos, about half a minute in all.
TEST(Fault, AnInterruptedSfmResumesFromItsLastFinishedStage) {
  if (!OnPath("colmap")) GTEST_SKIP() << "COLMAP is not installed (scripts/deps.sh installs it)";
  TempDir dir;
  WriteEightSyntheticPhotos(dir.File("site"));
  const auto [ref, ref_err] = RunToEnd({"sfm", dir.File("site"), "-o", dir.File("ref"), "--threads", "1"}, LogDir(dir));
  ASSERT_EQ(ref, 0) << ref_err;

  Process p({"sfm", dir.File("site"), "-o", dir.File("ws"), "--colmap", HeldColmap(dir, "mapper")}, LogDir(dir));
  pid_t held = 0;
  while (held == 0 && p.Running()) {
    held = FindChild(p.pid(), "mapper");
    if (held == 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_NE(held, 0) << "COLMAP's mapper never started: " << p.Stderr();
  kill(p.pid(), SIGINT);
  const int status = p.Wait();
  kill(held, SIGKILL);  // stopped, it cannot act on the SIGTERM candi sent it
  ASSERT_TRUE(WIFSIGNALED(status)) << p.Stderr();
  EXPECT_EQ(WTERMSIG(status), SIGINT);
  const std::string record = ReadBytes(dir.File("ws/sfm_stages.txt"));
  for (const char* stage : {"stage feature_extractor ", "stage match_features ", "stage matches_importer ",
                            "stage transitive_matching "})
    EXPECT_TRUE(Contains(record, stage)) << stage << " is recorded as finished: " << record;
  EXPECT_FALSE(Contains(record, "stage mapper")) << record;

  // Without --resume the run is refused, naming both ways on.
  const auto [again, again_err] = RunToEnd({"sfm", dir.File("site"), "-o", dir.File("ws")}, LogDir(dir));
  EXPECT_EQ(again, 2);
  EXPECT_TRUE(Contains(again_err, "--resume to continue it")) << again_err;
  // Resumed with other options: refused, naming what differs.
  const auto [other, other_err] =
      RunToEnd({"sfm", dir.File("site"), "-o", dir.File("ws"), "--resume", "--max-features", "999"}, LogDir(dir));
  EXPECT_EQ(other, 2);
  EXPECT_TRUE(Contains(other_err, "max_features 4096, now max_features 999")) << other_err;

  const std::string features = ReadBytes(dir.File("ws/logs/feature_extractor.log"));
  const auto [resumed, resumed_err] =
      RunToEnd({"sfm", dir.File("site"), "-o", dir.File("ws"), "--resume", "--threads", "2"}, LogDir(dir));
  ASSERT_EQ(resumed, 0) << resumed_err;
  EXPECT_TRUE(Contains(resumed_err, "feature_extractor (finished before)")) << resumed_err;
  EXPECT_EQ(ReadBytes(dir.File("ws/logs/feature_extractor.log")), features) << "extraction did not run again";
  for (const char* f : {"sparse/0/cameras.bin", "sparse/0/images.bin", "sparse/0/points3D.bin", "matches.txt"}) {
    const std::string a = ReadBytes(dir.File(std::string("ref/") + f));
    EXPECT_FALSE(a.empty()) << f;
    EXPECT_TRUE(a == ReadBytes(dir.File(std::string("ws/") + f))) << f << " differs from the run straight through";
  }
  EXPECT_TRUE(Contains(ReadBytes(dir.File("ws/sfm_stages.txt")), "stage image_undistorter "));
}

// Interrupted in transitive matching's second round (COLMAP verifying it, held at its start):
// the resumed run takes the first round's pairs out of the database again and gives the same
// matches and model as a run straight through. Eight photos matched one along the sequence, so
// that the rounds have pairs to add (exhaustive matching leaves none).
TEST(Fault, AnSfmInterruptedInTransitiveMatchingResumesToTheSameBytes) {
  if (!OnPath("colmap")) GTEST_SKIP() << "COLMAP is not installed (scripts/deps.sh installs it)";
  TempDir dir;
  WriteEightSyntheticPhotos(dir.File("site"));
  const std::vector<std::string> sequence = {"--matching", "sequential", "--sequential-overlap", "1"};
  std::vector<std::string> ref_args = {"sfm", dir.File("site"), "-o", dir.File("ref"), "--threads", "1"};
  ref_args.insert(ref_args.end(), sequence.begin(), sequence.end());
  const auto [ref, ref_err] = RunToEnd(ref_args, LogDir(dir));
  ASSERT_EQ(ref, 0) << ref_err;
  const std::string log = ReadBytes(dir.File("ref/logs/transitive_matching.log"));
  ASSERT_TRUE(Contains(log, "round 2: ")) << "the second round had pairs to add: " << log;

  std::vector<std::string> args = {"sfm", dir.File("site"), "-o", dir.File("ws"), "--colmap",
                                   HeldColmap(dir, "matches_importer", "round_2")};
  args.insert(args.end(), sequence.begin(), sequence.end());
  Process p(args, LogDir(dir));
  pid_t held = 0;
  while (held == 0 && p.Running()) {
    held = FindChild(p.pid(), "transitive_matches/round_2");
    if (held == 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_NE(held, 0) << "the second round's verification never started: " << p.Stderr();
  kill(p.pid(), SIGINT);
  const int status = p.Wait();
  kill(held, SIGKILL);
  ASSERT_TRUE(WIFSIGNALED(status)) << p.Stderr();
  const std::string record = ReadBytes(dir.File("ws/sfm_stages.txt"));
  EXPECT_TRUE(Contains(record, "stage matches_importer ")) << record;
  EXPECT_FALSE(Contains(record, "stage transitive_matching")) << record;
  EXPECT_TRUE(fs::exists(dir.File("ws/transitive_matches/round_1.txt")));

  args = {"sfm", dir.File("site"), "-o", dir.File("ws"), "--resume", "--threads", "2"};
  args.insert(args.end(), sequence.begin(), sequence.end());
  const auto [resumed, resumed_err] = RunToEnd(args, LogDir(dir));
  ASSERT_EQ(resumed, 0) << resumed_err;
  EXPECT_TRUE(Contains(resumed_err, "matches_importer (finished before)")) << resumed_err;
  EXPECT_EQ(ReadBytes(dir.File("ws/logs/transitive_matching.log")), log);
  for (const char* f : {"matches.txt", "transitive_matches/round_1.txt", "transitive_matches/round_2.txt",
                        "sparse/0/cameras.bin", "sparse/0/images.bin", "sparse/0/points3D.bin"}) {
    const std::string a = ReadBytes(dir.File(std::string("ref/") + f));
    EXPECT_FALSE(a.empty()) << f;
    EXPECT_TRUE(a == ReadBytes(dir.File(std::string("ws/") + f))) << f << " differs from the run straight through";
  }
}

TEST(Fault, AnInterruptedBuildLeavesFinishedFilesAndResumes) {
  TempDir dir;
  WriteCloud(dir.File("cloud.ply"), 100000, 6);
  WriteBytes(dir.File("scene.json"), FaultScene(4).dump());
  // The reference: one uninterrupted build.
  const auto [ref, ref_err] = RunToEnd({"build", dir.File("scene.json"), "-o", dir.File("ref")}, LogDir(dir));
  ASSERT_EQ(ref, 0) << ref_err;

  // Interrupted (SIGINT, through the real handler) once the first view is rendered: the build
  // sends it to itself after that checkpoint (CANDI_TEST_INTERRUPT_AFTER), so no timing between
  // this test and the build decides where it stops.
  Process p({"build", dir.File("scene.json"), "-o", dir.File("out")}, LogDir(dir), {"CANDI_TEST_INTERRUPT_AFTER=view_v0"});
  const int status = p.Wait();
  const std::string err = p.Stderr();
  ASSERT_TRUE(WIFSIGNALED(status)) << "the build ended before the interrupt: " << err;
  EXPECT_EQ(WTERMSIG(status), SIGINT);
  EXPECT_TRUE(Contains(err, "interrupted by SIGINT")) << err;
  EXPECT_TRUE(Temporaries(dir.path()).empty());
  EXPECT_FALSE(fs::exists(dir.File("out/archive.json"))) << "the build did not finish";
  // What it finished is complete.
  EXPECT_EQ(ReadBytes(dir.File("out/layers/hill.ply")), ReadBytes(dir.File("ref/layers/hill.ply")));
  EXPECT_TRUE(io::ReadPng(dir.File("out/renders/v0.png")).image8 == io::ReadPng(dir.File("ref/renders/v0.png")).image8);

  // Resumed: the foundation and the first view are reused, the rest done; the same archive.
  const auto [code, resumed_err] = RunToEnd({"build", dir.File("scene.json"), "-o", dir.File("out"), "--resume"}, LogDir(dir));
  ASSERT_EQ(code, 0) << resumed_err;
  EXPECT_TRUE(Contains(resumed_err, "layer hill (foundation): resumed")) << resumed_err;
  EXPECT_TRUE(Contains(resumed_err, "view v0: resumed")) << resumed_err;
  EXPECT_FALSE(Contains(resumed_err, "view v3: resumed")) << resumed_err;
  const json a = json::parse(ReadBytes(dir.File("out/archive.json")));
  EXPECT_EQ(a["layers"][1]["resumed"], true);
  EXPECT_EQ(a["views"][0]["resumed"], true);
  EXPECT_EQ(a["views"][3]["resumed"], false);
  for (const char* layer : {"cloud", "hill"})
    EXPECT_EQ(ReadBytes(dir.File(std::string("out/layers/") + layer + ".ply")),
              ReadBytes(dir.File(std::string("ref/layers/") + layer + ".ply"))) << layer;
  for (int v = 0; v < 4; ++v) {
    const std::string png = "/renders/v" + std::to_string(v) + ".png";
    EXPECT_TRUE(io::ReadPng(dir.File("out" + png)).image8 == io::ReadPng(dir.File("ref" + png)).image8) << png;
  }

  // A changed input is not resumed: the foundation's count.
  json scene = FaultScene(4);
  scene["layers"][1]["count"] = 21000;
  WriteBytes(dir.File("scene.json"), scene.dump());
  const auto [again, again_err] = RunToEnd({"build", dir.File("scene.json"), "-o", dir.File("out"), "--resume"}, LogDir(dir));
  ASSERT_EQ(again, 0) << again_err;
  EXPECT_FALSE(Contains(again_err, "layer hill (foundation): resumed")) << again_err;
  EXPECT_FALSE(Contains(again_err, "view v0: resumed")) << again_err;
  EXPECT_EQ(io::ReadPointCloud(dir.File("out/layers/hill.ply")).size(), 21000u);
}


// LAZ and COPC (issue 38) go through the same temporary file as every writer: a full disk, a
// read-only folder and an interrupt mid-write leave the earlier output under the target name and
// no temporary. (The COPC writer holds the points until Close(), so its writes all come last;
// spilled, its records go to a temporary folder beside the file first.)
TEST(Fault, LazAndCopcOnAFullDiskOrInterruptedKeepTheEarlierOutput) {
  TempDir dir;
  WriteCloud(dir.File("in.ply"), 600000, 7);  // ~3 MB of LAZ: more than the 1 MiB limit
  // A COPC file's records in memory, or spilled beside it (a budget of 1 MB: its spill then
  // meets the full disk first, and its folder is a temporary too).
  const std::vector<std::vector<std::string>> outputs = {
      {"out.laz"}, {"out.copc.laz"}, {"spilled.copc.laz", "--copc-memory", "1"}};
  for (const std::vector<std::string>& output : outputs) {
    const std::string& name = output[0];
    SCOPED_TRACE(name);
    const std::string out = dir.File(name);
    std::vector<std::string> args{"convert", dir.File("in.ply"), out};
    args.insert(args.end(), output.begin() + 1, output.end());
    WriteBytes(out, "an earlier output\n");
    const auto [code, err] = RunToEnd(args, LogDir(dir), {}, LimitFileSize);
    EXPECT_EQ(code, 2) << err;
    EXPECT_TRUE(Contains(err, out)) << err;
    if (output.size() > 1) {
      EXPECT_TRUE(Contains(err, "cannot write a spill file: File too large")) << err;
    } else {
      EXPECT_TRUE(Contains(err, "write failed: File too large")) << err;
      EXPECT_TRUE(Contains(err, "the destination is unchanged")) << err;
    }
    EXPECT_TRUE(ReadBytes(out) == "an earlier output\n");
    EXPECT_TRUE(Temporaries(dir.path()).empty());

    // Interrupted (SIGINT through the real handler) once 300,000 bytes are written.
    Process p(args, LogDir(dir), {"CANDI_TEST_INTERRUPT_AT_BYTE=300000"});
    const int status = p.Wait();
    const std::string interrupted = p.Stderr();
    ASSERT_TRUE(WIFSIGNALED(status)) << "the write ended before the interrupt: " << interrupted;
    EXPECT_EQ(WTERMSIG(status), SIGINT);
    EXPECT_TRUE(Contains(interrupted, "interrupted by SIGINT")) << interrupted;
    EXPECT_TRUE(ReadBytes(out) == "an earlier output\n");
    EXPECT_TRUE(Temporaries(dir.path()).empty());

    // Unlimited, the same command writes the file in full.
    const auto [ok, ok_err] = RunToEnd(args, LogDir(dir));
    ASSERT_EQ(ok, 0) << ok_err;
    EXPECT_GT(fs::file_size(out), size_t{1} << 20);
    EXPECT_EQ(io::ReadPointCloud(out).size(), 600000u);
    EXPECT_TRUE(Temporaries(dir.path()).empty());
  }
  EXPECT_TRUE(ReadBytes(dir.File("out.copc.laz")).substr(94) ==
              ReadBytes(dir.File("spilled.copc.laz")).substr(94))
      << "spilled or in memory, the same file (but the creation date)";

  // A real full disk (a 1 MiB tmpfs) where the tests may mount one.
  const SmallDisk small(dir.File("disk"));
  if (!small.mounted) GTEST_SKIP() << small.why << ": the file-size limit above stood in for a full disk";
  const std::string& disk = small.path;
  for (const std::string name : {"out.laz", "out.copc.laz"}) {
    SCOPED_TRACE(name);
    const std::string out = disk + "/" + name;
    WriteBytes(out, "an earlier output\n");
    const auto [code, err] = RunToEnd({"convert", dir.File("in.ply"), out}, LogDir(dir));
    EXPECT_EQ(code, 2) << err;
    EXPECT_TRUE(Contains(err, out)) << err;
    EXPECT_TRUE(Contains(err, "No space left on device")) << err;
    EXPECT_TRUE(ReadBytes(out) == "an earlier output\n");
    EXPECT_TRUE(Temporaries(disk).empty());
  }
}

TEST(Fault, LazAndCopcIntoAFolderThatRefusesFilesAreRefusedByName) {
  TempDir dir;
  WriteCloud(dir.File("in.ply"), 1000, 8);
  // root may write into a folder of mode 0555; /proc refuses new files to everyone.
  const std::string folder = geteuid() == 0 ? std::string("/proc") : dir.File("locked");
  if (geteuid() != 0) {
    fs::create_directories(folder);
    chmod(folder.c_str(), 0555);
  }
  // The last: a COPC file spilled from the start (a budget of 0.001 MB), whose spill folder
  // cannot be made there either.
  for (const std::string name :
       {"candi_fault_test.laz", "candi_fault_test.copc.laz", "candi_fault_spilled.copc.laz"}) {
    const std::string out = folder + "/" + name;
    std::vector<std::string> args{"convert", dir.File("in.ply"), out};
    if (name == "candi_fault_spilled.copc.laz") args.insert(args.end(), {"--copc-memory", "0.001"});
    const auto [code, err] = RunToEnd(args, LogDir(dir));
    EXPECT_EQ(code, 2) << err;
    EXPECT_TRUE(Contains(err, out) || Contains(err, folder)) << err;
    if (args.size() > 3) {
      EXPECT_TRUE(Contains(err, "cannot create the COPC file's spill folder")) << err;
    }
    EXPECT_FALSE(fs::exists(out));
  }
  if (geteuid() != 0) {
    chmod(folder.c_str(), 0755);
    EXPECT_TRUE(fs::is_empty(folder));
  }
}

// What replacing an archive or republishing a site leaves that cannot be removed is named on
// stderr (the command still succeeds: the new output is in place), never left without a word.
TEST(Fault, AnOldCopyThatCannotBeRemovedIsNamed) {
  TempDir dir;
  WriteCloud(dir.File("cloud.ply"), 5000, 5);
  const std::string archive = dir.File("out.archive");
  ASSERT_EQ(RunToEnd({"pack", dir.File("cloud.ply"), "-o", archive}, LogDir(dir)).first, 0);
  const std::vector<std::string> keep_old = {
      "LD_PRELOAD=" CANDI_FAULT_INJECT_LIB, "CANDI_FAULT_REMOVE=.candi-old-",
      std::string("ASAN_OPTIONS=verify_asan_link_order=0:") +
          (getenv("ASAN_OPTIONS") ? getenv("ASAN_OPTIONS") : "")};
  const auto [code, err] =
      RunToEnd({"pack", dir.File("cloud.ply"), "-o", archive}, LogDir(dir), keep_old);
  EXPECT_EQ(code, 0) << err;
  std::vector<std::string> old;
  for (const auto& e : fs::directory_iterator(dir.path())) {
    if (Contains(e.path().filename().string(), ".candi-old-")) old.push_back(e.path().string());
  }
  ASSERT_EQ(old.size(), 1u) << "the injected fault kept the old archive";
  EXPECT_TRUE(Contains(err, old[0]) && Contains(err, "remove it by hand")) << err;
  fs::remove_all(old[0]);

  // A republished site: the old data, moved into the build folder inside the site, stays.
  const std::string site = dir.File("site");
  ASSERT_EQ(RunToEnd({"publish", archive, "-o", site, "-L", "4"}, LogDir(dir)).first, 0);
  std::vector<std::string> keep_build = keep_old;
  keep_build[1] = "CANDI_FAULT_REMOVE=.candi-publish-";
  const auto [again, again_err] =
      RunToEnd({"publish", archive, "-o", site, "-L", "3"}, LogDir(dir), keep_build);
  EXPECT_EQ(again, 0) << again_err;
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(site)) {
    if (Contains(e.path().filename().string(), ".candi-publish-"))
      left.push_back(e.path().string());
  }
  ASSERT_EQ(left.size(), 1u);
  EXPECT_TRUE(Contains(again_err, left[0]) && Contains(again_err, "remove it by hand"))
      << again_err;
  EXPECT_TRUE(fs::exists(left[0] + "/data/0/3.bin")) << "what is left is the old data (L = 4)";
  EXPECT_FALSE(fs::exists(site + "/data/0/3.bin")) << "the site's data is the new (L = 3)";
  // The next publish removes what an earlier one left (its process is gone), and says so.
  const auto [third, third_err] =
      RunToEnd({"publish", archive, "-o", site, "-L", "3"}, LogDir(dir));
  EXPECT_EQ(third, 0) << third_err;
  EXPECT_FALSE(fs::exists(left[0]));
  EXPECT_TRUE(Contains(third_err, left[0])) << third_err;
}

}  // namespace
}  // namespace candi::testing

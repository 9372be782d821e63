#include "reconstruction/photogrammetry/sfm/colmap_runner.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

#include "core/check.h"
#include "reconstruction/photogrammetry/georef/similarity_fit.h"
#include "reconstruction/photogrammetry/scenes/campaign.h"
#include "reconstruction/photogrammetry/sfm/colmap_database.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"
#include "tests/util/test_util.h"

namespace candi::photogrammetry {
namespace {

using candi::testing::FileExists;
using candi::testing::ReadBytes;
using candi::testing::RunCommand;
using candi::testing::TempDir;
using candi::testing::WriteBytes;

// Writes a file, creating its folder.
void Put(const std::string& path, const std::string& bytes) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  WriteBytes(path, bytes);
}

bool ColmapAvailable() { return RunCommand("colmap help").code == 0; }

#define REQUIRE_COLMAP()                                                     \
  if (!ColmapAvailable()) {                                                  \
    GTEST_SKIP() << "COLMAP is not installed here (Debian: apt install colmap)"; \
  }

template <typename F>
std::string InputErrorText(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError";
  return "";
}

// A `w` x `h` binary PGM of uniform noise (no EXIF; PGM carries none).
void WriteNoisePgm(const std::string& path, int w, int h, uint64_t seed) {
  std::string bytes = "P5 " + std::to_string(w) + " " + std::to_string(h) + " 255\n";
  uint64_t state = seed * 0x9E3779B97F4A7C15ull + 1;
  for (int i = 0; i < w * h; ++i) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    bytes.push_back(static_cast<char>(state >> 56));
  }
  Put(path, bytes);
}

TEST(SfmOptions, DefaultsPassAndBadValuesNameTheField) {
  SfmOptions o;
  EXPECT_NO_THROW(o.Check());
  o.max_features = 10;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = SfmOptions();
  o.camera_model = "FISH";
  try {
    o.Check();
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("SfmOptions::camera_model = FISH"), std::string::npos);
  }
  o = SfmOptions();
  o.threads = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = SfmOptions();
  o.pairs.strategy = PairStrategy::kPositional;
  try {
    o.Check();
    ADD_FAILURE() << "positional matching without priors";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("SfmOptions::priors"), std::string::npos) << e.what();
  }
  o.priors = "priors.csv";
  EXPECT_NO_THROW(o.Check());
}

TEST(ColmapVersion, ParsesBanners) {
  const ColmapVersion v = ParseColmapVersion(
      "COLMAP 3.8 -- Structure-from-Motion and Multi-View Stereo\n"
      "              (Commit Unknown on Unknown without CUDA)\n\nUsage:\n  colmap [command]\n");
  EXPECT_EQ(v.version, "3.8");
  EXPECT_FALSE(v.cuda);
  const ColmapVersion w = ParseColmapVersion(
      "COLMAP 3.9.1 -- Structure-from-Motion and Multi-View Stereo\n"
      "              (Commit 0d9d4e8 on 2024-01-05 with CUDA)\n");
  EXPECT_EQ(w.version, "3.9.1");
  EXPECT_TRUE(w.cuda);
  EXPECT_THROW(ParseColmapVersion("bash: colmap: command not found"), std::invalid_argument);
}

TEST(ColmapVersion, ParsesTheInstalledColmap) {
  REQUIRE_COLMAP();
  const ColmapVersion v = ParseColmapVersion(RunCommand("colmap help").output);
  EXPECT_FALSE(v.version.empty());
  EXPECT_TRUE(v.version[0] >= '3' && v.version[0] <= '9') << v.version;
  // Debian's build has no CUDA (BUILD_NOTES.md): then the GPU must stay off.
  if (RunCommand("colmap help").output.find("without CUDA") != std::string::npos) {
    EXPECT_FALSE(v.cuda);
  }
}

std::vector<std::string> Flags(const SfmStage& stage) {
  std::vector<std::string> flags;
  for (const std::string& a : stage.argv) {
    if (a.rfind("--", 0) == 0) flags.push_back(a);
  }
  return flags;
}

std::string Value(const SfmStage& stage, const std::string& flag) {
  for (size_t i = 0; i + 1 < stage.argv.size(); ++i) {
    if (stage.argv[i] == flag) return stage.argv[i + 1];
  }
  return "<absent>";
}

TEST(BuildSfmStages, CpuArgvAndDeterministicMatching) {
  SfmOptions o;
  o.colmap = "/opt/colmap";
  o.max_features = 2000;
  o.max_image_size = 800;
  const std::vector<SfmStage> stages = BuildSfmStages(o, "/w s", /*cuda=*/false);
  ASSERT_EQ(stages.size(), 6u);
  EXPECT_EQ(stages[0].argv[0], "/opt/colmap");
  EXPECT_EQ(stages[0].argv[1], "feature_extractor");
  EXPECT_EQ(Value(stages[0], "--SiftExtraction.use_gpu"), "0");
  EXPECT_EQ(Value(stages[0], "--SiftExtraction.max_num_features"), "2000");
  EXPECT_EQ(Value(stages[0], "--SiftExtraction.max_image_size"), "800");
  EXPECT_EQ(Value(stages[0], "--ImageReader.single_camera"), "1");
  EXPECT_EQ(Value(stages[0], "--image_path"), "/w s/images");  // one argv element, no quoting
  // Matching is candi's own (no argv); COLMAP verifies the raw matches and maps on one thread.
  EXPECT_EQ(stages[1].name, kMatchStage);
  EXPECT_TRUE(stages[1].argv.empty());
  EXPECT_EQ(stages[2].argv[1], "matches_importer");
  EXPECT_EQ(Value(stages[2], "--match_type"), "raw");
  EXPECT_EQ(Value(stages[2], "--match_list_path"), "/w s/matches.txt");
  EXPECT_EQ(Value(stages[2], "--SiftMatching.num_threads"), "1");
  // Transitive matching is candi's too (it runs COLMAP's verification itself).
  EXPECT_EQ(stages[3].name, kTransitiveStage);
  EXPECT_TRUE(stages[3].argv.empty());
  EXPECT_EQ(stages[4].argv[1], "mapper");
  EXPECT_EQ(Value(stages[4], "--Mapper.num_threads"), "1");
  EXPECT_EQ(Value(stages[4], "--random_seed"), "0");
  EXPECT_EQ(Value(stages[4], "--output_path"), "/w s/sparse");
  EXPECT_EQ(Value(stages[5], "--output_path"), "/w s/dense");
  EXPECT_EQ(Value(stages[5], "--max_image_size"), "800");
  EXPECT_EQ(Value(BuildSfmStages(o, "/w", /*cuda=*/true)[0], "--SiftExtraction.use_gpu"), "1");
}

// Every option candi passes is one the installed COLMAP lists in `colmap <command> -h`.
TEST(BuildSfmStages, OptionNamesAreAcceptedByTheInstalledColmap) {
  REQUIRE_COLMAP();
  for (const SfmStage& stage : BuildSfmStages(SfmOptions{}, "/w", false)) {
    if (stage.argv.empty()) continue;  // candi's own stage
    const std::string help = RunCommand("colmap " + stage.argv[1] + " -h").output;
    ASSERT_NE(help.find("--help"), std::string::npos) << stage.name << ": " << help;
    for (const std::string& flag : Flags(stage)) {
      EXPECT_NE(help.find("  " + flag + " "), std::string::npos) << stage.name << " lacks " << flag;
    }
  }
}

TEST(ListImages, ImagesSortedOthersIgnored) {
  TempDir dir;
  for (const char* f : {"b.JPG", "a.jpg", "c.png", "d.TIFF", "notes.txt", "K.txt", "e.pgm"}) {
    Put(dir.File(f), "x");
  }
  std::filesystem::create_directory(dir.File("sub.jpg"));  // a folder is not an image
  std::vector<std::string> ignored;
  const std::vector<std::string> images = ListImages(dir.path(), &ignored);
  EXPECT_EQ(images, (std::vector<std::string>{"a.jpg", "b.JPG", "c.png", "d.TIFF", "e.pgm"}));
  EXPECT_EQ(ignored, (std::vector<std::string>{"K.txt", "notes.txt"}));
  EXPECT_NE(InputErrorText([&] { ListImages(dir.File("absent"), nullptr); }).find("no such folder"),
            std::string::npos);
  EXPECT_NE(InputErrorText([&] { ListImages(dir.File("a.jpg"), nullptr); }).find("not a folder"),
            std::string::npos);
}

TEST(ListImages, ACampaignFolderGivesItsSessionsPhotos) {
  TempDir dir;
  for (const char* f : {"s2/s2_0001.jpg", "s1/s1_0002.jpg", "s1/s1_0001.jpg", "s1/notes.txt", "uav/uav_0001.png"}) {
    Put(dir.File(f), "x");
  }
  std::vector<std::string> ignored;
  EXPECT_EQ(ListImages(dir.path(), &ignored),
            (std::vector<std::string>{"s1/s1_0001.jpg", "s1/s1_0002.jpg", "s2/s2_0001.jpg", "uav/uav_0001.png"}));
  EXPECT_EQ(ignored, (std::vector<std::string>{"s1/notes.txt"}));
  // A folder with photos of its own: its subfolders are not searched.
  Put(dir.File("top.jpg"), "x");
  EXPECT_EQ(ListImages(dir.path(), nullptr), (std::vector<std::string>{"top.jpg"}));
}

TEST(RunLogged, ExitCodeLogAndMissingExecutable) {
  TempDir dir;
  const std::string log = dir.File("x.log");
  EXPECT_EQ(RunLogged({"sh", "-c", "echo out; echo err >&2; exit 3", "ignored"}, log), 3);
  EXPECT_EQ(ReadBytes(log), "out\nerr\n");
  // Arguments are not interpreted by a shell.
  EXPECT_EQ(RunLogged({"echo", "$HOME;", "`x`"}, log), 0);
  EXPECT_EQ(ReadBytes(log), "out\nerr\n$HOME; `x`\n");
  const std::string text = InputErrorText([&] { RunLogged({dir.File("no-such-colmap"), "help"}, log); });
  EXPECT_NE(text.find("no-such-colmap"), std::string::npos) << text;
  EXPECT_NE(text.find("No such file"), std::string::npos) << text;
}

TEST(TailOfFile, KeepsTheLastLines) {
  TempDir dir;
  std::string text;
  for (int i = 0; i < 30; ++i) text += "line " + std::to_string(i) + "\n";
  Put(dir.File("l"), text);
  const std::string tail = TailOfFile(dir.File("l"), 20);
  EXPECT_EQ(tail.substr(0, 8), "line 10\n");
  EXPECT_EQ(tail.substr(tail.size() - 8), "line 29\n");
  EXPECT_EQ(TailOfFile(dir.File("absent"), 20), "");
}

TEST(ParseFeatureExtractionLog, FindsPhotosWithoutExifFocal) {
  TempDir dir;
  Put(dir.File("fe.log"),
             "Processed file [1/2]\n  Name:            a.jpg\n  Dimensions:      2832 x 2128\n"
             "  Focal Length:    2832.00px (Prior)\n  Features:        1706\n"
             "Processed file [2/2]\n  Name:            b.png\n  Dimensions:      200 x 150\n"
             "  Focal Length:    240.00px\n  Features:        94\n");
  SfmSummary s;
  ParseFeatureExtractionLog(dir.File("fe.log"), &s);
  EXPECT_EQ(s.no_exif, std::vector<std::string>{"b.png"});
  EXPECT_DOUBLE_EQ(s.default_focal_px, 240.0);
}

// COLMAP's own log of a folder with a photo of another size under one shared camera, and EXIF
// focal priors.
TEST(ParseFeatureExtractionLog, FindsPhotosOfAnotherSizeAndTheFocalPriors) {
  TempDir dir;
  Put(dir.File("fe.log"),
      "Processed file [1/3]\n  Name:            b.jpg\n  Dimensions:      160 x 120\n"
      "  Camera:          #1 - SIMPLE_RADIAL\n  Focal Length:    190.50px (Prior)\n  Features:        59\n"
      "Processed file [2/3]\n  Name:            c.pgm\n"
      "  ERROR: Single camera specified, but images have different dimensions.\n"
      "Processed file [3/3]\n  Name:            a.jpg\n  Dimensions:      160 x 120\n"
      "  Focal Length:    250.00px (Prior)\n");
  SfmSummary s;
  ParseFeatureExtractionLog(dir.File("fe.log"), &s);
  EXPECT_EQ(s.other_size, std::vector<std::string>{"c.pgm"});
  EXPECT_TRUE(s.no_exif.empty());
  ASSERT_EQ(s.focal_priors.size(), 2u);
  EXPECT_EQ(s.focal_priors[0].first, "a.jpg");
  EXPECT_DOUBLE_EQ(s.focal_priors[0].second, 250.0);
  EXPECT_DOUBLE_EQ(s.focal_priors[1].second, 190.5);
}

// The fraction of a stage from COLMAP's own counters, the later of them winning.
TEST(FractionInLog, ReadsTheLastCounter) {
  EXPECT_EQ(FractionInLog("", 10), -1.0);
  EXPECT_EQ(FractionInLog("Loading database\n", 10), -1.0);
  EXPECT_DOUBLE_EQ(FractionInLog("Processed file [1/4]\n  Name: a\nProcessed file [3/4]\n  Name: c\n", 0), 0.75);
  const std::string mapper = "Undistorting image [9/9]\nRegistering image #4 (3)\nRegistering image #7 (5)\n";
  EXPECT_DOUBLE_EQ(FractionInLog(mapper, 20), 0.25);
  EXPECT_DOUBLE_EQ(FractionInLog(mapper, 0), 1.0) << "without the count of images, the bracket counter";
  EXPECT_DOUBLE_EQ(FractionInLog("Registering image #7 (30)\n", 20), 1.0) << "never beyond the end";
  EXPECT_EQ(FractionInLog("[3/0]", 5), -1.0);
}

// Photos with the same bytes under other names (a session copied twice) are found by size and
// hash, in groups by name; others of the same size are not.
TEST(IdenticalFiles, GroupsCopiesAndNothingElse) {
  TempDir dir;
  WriteNoisePgm(dir.File("in/a.pgm"), 40, 30, 1);
  WriteNoisePgm(dir.File("in/b.pgm"), 40, 30, 2);
  WriteNoisePgm(dir.File("in/s2/c.pgm"), 40, 30, 1);
  WriteNoisePgm(dir.File("in/d.pgm"), 40, 30, 1);
  WriteNoisePgm(dir.File("in/e.pgm"), 41, 30, 2);
  const auto groups = IdenticalFiles(dir.File("in"), {"a.pgm", "b.pgm", "d.pgm", "e.pgm", "s2/c.pgm"});
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0], (std::vector<std::string>{"a.pgm", "d.pgm", "s2/c.pgm"}));
  EXPECT_TRUE(IdenticalFiles(dir.File("in"), {"a.pgm", "b.pgm"}).empty());
}

TEST(ParseFeatureExtractionLog, ListsThePhotosByNameWhateverOrderTheThreadsLogged) {
  TempDir dir;
  Put(dir.File("fe.log"),
      "  Name:            d.png\n  Focal Length:    240.00px\n"
      "  Name:            b.png\n  Focal Length:    240.00px\n"
      "  Name:            c.png\nERROR: Failed to read image\n"
      "  Name:            a.png\nERROR: Failed to read image\n");
  SfmSummary s;
  ParseFeatureExtractionLog(dir.File("fe.log"), &s);
  EXPECT_EQ(s.no_exif, (std::vector<std::string>{"b.png", "d.png"}));
  EXPECT_EQ(s.unreadable, (std::vector<std::string>{"a.png", "c.png"}));
}

TEST(RunSfm, ColmapAbsentSaysHowToInstall) {
  TempDir dir;
  for (const char* f : {"a.jpg", "b.jpg"}) Put(dir.File(std::string("in/") + f), f);  // not copies
  SfmOptions o;
  o.colmap = dir.File("missing/colmap");
  const std::string text = InputErrorText([&] { RunSfm(o, dir.File("in"), dir.File("ws")); });
  EXPECT_NE(text.find("COLMAP was not found"), std::string::npos) << text;
  EXPECT_NE(text.find("apt install colmap"), std::string::npos) << text;
  EXPECT_NE(text.find("--colmap"), std::string::npos) << text;
}

TEST(RunSfm, RefusesFoldersWithoutTwoImages) {
  TempDir dir;
  std::filesystem::create_directories(dir.File("empty"));
  EXPECT_NE(InputErrorText([&] { RunSfm({}, dir.File("empty"), dir.File("ws")); }).find("no images"),
            std::string::npos);
  Put(dir.File("docs/readme.txt"), "x");
  EXPECT_NE(InputErrorText([&] { RunSfm({}, dir.File("docs"), dir.File("ws")); }).find("no images"),
            std::string::npos);
  Put(dir.File("one/only.jpg"), "x");
  const std::string one = InputErrorText([&] { RunSfm({}, dir.File("one"), dir.File("ws")); });
  EXPECT_NE(one.find("only one image (only.jpg)"), std::string::npos) << one;
  EXPECT_NE(one.find("at least 2"), std::string::npos) << one;
  EXPECT_FALSE(FileExists(dir.File("ws/database.db")));
}

TEST(RunSfm, RefusesToOverwriteAPreviousRun) {
  TempDir dir;
  for (const char* f : {"a.jpg", "b.jpg"}) Put(dir.File(std::string("in/") + f), f);  // not copies
  Put(dir.File("ws/database.db"), "precious");
  SfmOptions o;
  o.colmap = dir.File("missing/colmap");
  const std::string text = InputErrorText([&] { RunSfm(o, dir.File("in"), dir.File("ws")); });
  EXPECT_NE(text.find("--overwrite"), std::string::npos) << text;
  EXPECT_EQ(ReadBytes(dir.File("ws/database.db")), "precious");
}

// Real COLMAP on two unrelated noise images (no EXIF, a non-image file beside them): the mapper
// finds no model and the message says why. A few seconds.
TEST(RunSfm, UnrelatedImagesGiveNoModelMessage) {
  REQUIRE_COLMAP();
  TempDir dir;
  WriteNoisePgm(dir.File("in/n0.pgm"), 160, 120, 1);
  WriteNoisePgm(dir.File("in/n1.pgm"), 160, 120, 2);
  Put(dir.File("in/notes.txt"), "not an image");
  SfmOptions o;
  o.threads = 1;
  std::vector<std::string> stages;
  const std::string text = InputErrorText([&] {
    RunSfm(o, dir.File("in"), dir.File("ws"),
           [&](const std::string& stage, int, int, double, bool done, double) {
             if (done) stages.push_back(stage);
           });
  });
  EXPECT_NE(text.find("no model: the images may not overlap"), std::string::npos) << text;
  EXPECT_EQ(stages, (std::vector<std::string>{"feature_extractor", kMatchStage, "matches_importer", kTransitiveStage}));
  EXPECT_TRUE(FileExists(dir.File("ws/logs/mapper.log")));
  EXPECT_TRUE(FileExists(dir.File("ws/images/n0.pgm")));
  EXPECT_FALSE(FileExists(dir.File("ws/images/notes.txt")));
}

// Files with image names that COLMAP cannot decode: skipped with a warning; fewer than 2 left is
// an error naming them.
TEST(RunSfm, UnreadableImagesAreNamed) {
  REQUIRE_COLMAP();
  TempDir dir;
  Put(dir.File("in/a.jpg"), "not a jpeg");
  WriteNoisePgm(dir.File("in/n0.pgm"), 160, 120, 1);
  SfmOptions o;
  o.threads = 1;
  const std::string text = InputErrorText([&] { RunSfm(o, dir.File("in"), dir.File("ws")); });
  EXPECT_NE(text.find("could not use 1 of the 2 images (a.jpg): corrupt or not images"), std::string::npos) << text;
}

// Copies are left out before any work: a folder of one photo and its copy is a folder of one.
TEST(RunSfm, CopiesOfOnePhotoAreOnePhoto) {
  TempDir dir;
  WriteNoisePgm(dir.File("in/n0.pgm"), 160, 120, 1);
  WriteNoisePgm(dir.File("in/n0_copy.pgm"), 160, 120, 1);
  const std::string text = InputErrorText([&] { RunSfm(SfmOptions(), dir.File("in"), dir.File("ws")); });
  EXPECT_NE(text.find("only one distinct photo (n0.pgm; the others are copies of it)"), std::string::npos) << text;
  EXPECT_FALSE(FileExists(dir.File("ws"))) << "nothing is written";
}

// Photos of two sizes under one shared camera: COLMAP skips those of the other size; with fewer
// than two left the error names them and the way out. A few seconds.
TEST(RunSfm, APhotoOfAnotherSizeUnderOneCameraIsNamed) {
  REQUIRE_COLMAP();
  TempDir dir;
  WriteNoisePgm(dir.File("in/a.pgm"), 160, 120, 1);
  WriteNoisePgm(dir.File("in/b.pgm"), 200, 150, 2);
  SfmOptions o;
  o.threads = 1;
  const std::string text = InputErrorText([&] { RunSfm(o, dir.File("in"), dir.File("ws")); });
  EXPECT_NE(text.find("could not use 1 of the 2 images (b.pgm): other sizes than the first"), std::string::npos)
      << text;
  EXPECT_NE(text.find("--camera-per-image"), std::string::npos) << text;
}

// A real COLMAP stage failure (the matcher aborts on an empty database): exit status and the end
// of the log, without the stack-trace frames.
TEST(RunSfmStage, FailureReportsExitStatusAndLogTail) {
  REQUIRE_COLMAP();
  TempDir dir;
  const SfmStage stage{"exhaustive_matcher",
                       {"colmap", "exhaustive_matcher", "--database_path", dir.File("empty.db"),
                        "--SiftMatching.use_gpu", "0"}};
  int calls = 0;
  const std::string text = InputErrorText([&] {
    RunSfmStage(stage, dir.File("m.log"), 2, 4, [&](const std::string&, int, int, double, bool, double) { ++calls; });
  });
  EXPECT_NE(text.find("colmap exhaustive_matcher "), std::string::npos) << text;
  EXPECT_TRUE(text.find("killed by signal") != std::string::npos ||
              text.find("exit code") != std::string::npos) << text;
  EXPECT_NE(text.find("m.log"), std::string::npos) << text;
  EXPECT_EQ(text.find("    @ "), std::string::npos) << text;
  EXPECT_EQ(calls, 1);  // started, never done
  EXPECT_NE(ReadBytes(dir.File("m.log")).find("$ colmap exhaustive_matcher --database_path"),
            std::string::npos);
}

// The Sceaux photos end to end, downscaled (slow: minutes on 2 cores).
TEST(RunSfm, SceauxRegistersAlmostAllPhotos) {
  CANDI_REQUIRE_SLOW_TESTS();
  CANDI_REQUIRE_SHARED_DATA(photos, "photos/sceaux_castle");
  REQUIRE_COLMAP();
  TempDir dir;
  SfmOptions o;
  o.max_image_size = 800;
  o.max_features = 2000;
  const auto start = std::chrono::steady_clock::now();
  const SfmSummary s = RunSfm(o, photos, dir.File("ws"));
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::fprintf(stderr, "Sceaux SfM at 800 px, 2000 features: %.1f s, %zu/%zu registered, %zu points, "
               "%.3f px\n", seconds, s.registered.size(), s.images.size(), s.points,
               s.mean_reprojection_error);
  EXPECT_EQ(s.images.size(), 11u);
  EXPECT_EQ(s.ignored, std::vector<std::string>{"K.txt"});
  EXPECT_GE(s.registered.size(), 10u);
  EXPECT_GT(s.points, 1000u);
  EXPECT_LT(s.mean_reprojection_error, 1.5);
  EXPECT_TRUE(s.no_exif.empty());
  // A COLMAP dense workspace: undistorted images and a PINHOLE model that this reader reads.
  const ColmapModel dense = ReadColmapModel(dir.File("ws/dense/sparse"));
  EXPECT_EQ(dense.images.size(), s.registered.size());
  EXPECT_EQ(dense.cameras.begin()->second.model, "PINHOLE");
  EXPECT_LE(std::max(dense.cameras.begin()->second.width, dense.cameras.begin()->second.height), 800);
  for (const auto& [id, image] : dense.images) {
    EXPECT_TRUE(FileExists(dir.File("ws/dense/images/" + image.name))) << image.name;
  }
}


// The campaign issue's small case: 60 photos of 320 px in three sessions (priors with gps_sigma > 0).
Campaign SixtyPhotoCampaign(const std::string& site, double gps_sigma) {
  CampaignOptions c;
  c.photos = 60;
  c.width = 320;
  c.chunks = 3;
  c.gps_sigma = gps_sigma;
  return WriteCampaign(c, site);
}

// A model's camera centres by file name (the session folder left out).
std::map<std::string, Eigen::Vector3d> CentresByFile(const ColmapModel& model) {
  std::map<std::string, Eigen::Vector3d> centres;
  for (const auto& [id, image] : model.images) {
    centres[std::filesystem::path(image.name).filename().string()] =
        -(image.cam_from_world_rotation.conjugate() * image.cam_from_world_translation);
  }
  return centres;
}

// The campaign issue's CI case: 60 photos of 320 px in three sessions around a building, with
// GPS-like priors. Every photo registers; after one similarity onto the truth the camera centres
// agree to a few millimetres, and the walk's first and last photos (different sessions, the loop)
// agree as well as any: sequential matching alone leaves the loop open.
TEST(RunSfm, ACampaignOfSixtyPhotosInThreeSessionsRegistersAndClosesItsLoop) {
  REQUIRE_COLMAP();
  TempDir dir;
  const std::string site = dir.File("site");
  const Campaign campaign = SixtyPhotoCampaign(site, 3.0);
  SfmOptions o;
  o.priors = site + "/priors.csv";
  o.threads = 2;
  const SfmSummary s = RunSfm(o, site, dir.File("work"));
  EXPECT_EQ(s.images.size(), 60u);
  EXPECT_EQ(s.registered.size(), 60u);
  EXPECT_NE(s.matcher.find("retrieval"), std::string::npos) << s.matcher;
  EXPECT_NE(s.matcher.find("positions"), std::string::npos) << s.matcher;
  EXPECT_NE(s.matcher.find("transitive"), std::string::npos) << s.matcher;
  EXPECT_LT(s.pairs_tried, 60u * 59 / 2);
  // Transitive matching tried pairs beyond the first ones, and COLMAP verified them (its rounds'
  // lists are there and every pair of the database was matched by one list or the other).
  const std::set<std::pair<std::string, std::string>> matched = MatchedPairNames(dir.File("work/database.db"));
  EXPECT_GT(std::filesystem::file_size(dir.File("work/transitive_matches/round_1.txt")), 0u);
  EXPECT_LE(matched.size(), s.pairs_tried);
  EXPECT_GT(s.pairs_verified, 120u);
  // Camera centres against the truth, after the similarity that fits them best.
  std::map<std::string, Eigen::Vector3d> estimated = CentresByFile(ReadColmapModel(s.model_dir));
  std::vector<Eigen::Vector3d> from, to;
  std::vector<std::string> names;
  for (const CampaignPhoto& p : campaign.photos) {
    if (!estimated.count(p.name)) continue;
    from.push_back(estimated[p.name]);
    to.push_back(p.camera.Center());
    names.push_back(p.name);
  }
  ASSERT_EQ(from.size(), 60u);
  const Sim3 t = UmeyamaSimilarity(from, to, std::vector<double>(from.size(), 1.0), true);
  double sum_sq = 0, worst = 0;
  std::map<std::string, double> error;
  for (size_t i = 0; i < from.size(); ++i) {
    error[names[i]] = (t * from[i] - to[i]).norm();
    sum_sq += error[names[i]] * error[names[i]];
    worst = std::max(worst, error[names[i]]);
  }
  const double rms = std::sqrt(sum_sq / from.size());
  std::printf("camera centres against the truth: RMS %.2f mm, worst %.2f mm\n", 1e3 * rms, 1e3 * worst);
  EXPECT_LT(rms, 0.010);
  EXPECT_LT(worst, 0.030);
  // The loop: the walk's first photo (session s1) and the last of the same row (session s3).
  const CampaignPhoto* last = nullptr;
  for (const CampaignPhoto& p : campaign.photos)
    if (p.terrace == 0 && p.row == 0) last = &p;
  ASSERT_NE(last, nullptr);
  const std::string first = campaign.photos.front().name;
  const Eigen::Vector3d true_gap = last->camera.Center() - campaign.photos.front().camera.Center();
  const Eigen::Vector3d gap = t * estimated[last->name] - t * estimated[first];
  std::printf("loop: %s to %s, %.3f m apart, closed to %.2f mm\n", first.c_str(), last->name.c_str(),
              true_gap.norm(), 1e3 * (gap - true_gap).norm());
  EXPECT_LT((gap - true_gap).norm(), 0.010);
}


// The same campaign mapped in chunks: each session apart, tied by its own targets alone (the
// sessions share no photo), then adjusted as one (points joined where matches link two sessions,
// the chunks' copies of the camera made one again), in the survey frame. The camera centres are
// compared with the truth directly, no similarity fitted (measured: tied alone 12.8 mm RMS, worst
// 23 mm; adjusted 5.2 mm, worst 13.5 mm; the check targets 2.2 mm).
TEST(RunSfm, ACampaignMappedInChunksIsTiedByItsTargetsIntoTheSurveyFrame) {
  REQUIRE_COLMAP();
  TempDir dir;
  const std::string site = dir.File("site");
  const Campaign campaign = SixtyPhotoCampaign(site, 0.0);
  SfmOptions o;
  o.threads = 2;
  o.chunks.targets = site + "/targets.csv";
  o.chunks.picks = site + "/picks.csv";
  const SfmSummary s = RunSfm(o, site, dir.File("work"));
  ASSERT_EQ(s.chunked.chunks.size(), 3u);
  for (const ChunkResult& k : s.chunked.chunks) {
    EXPECT_TRUE(k.tied) << k.name << ": " << k.reason;
    EXPECT_EQ(k.registered, 20u) << k.name;
    EXPECT_GE(k.control_used, 3) << k.name;
    std::printf("chunk %s: control RMSE %.1f mm, check %.1f mm\n", k.name.c_str(), 1e3 * k.control.d3,
                1e3 * k.check.d3);
    // Measured 4, 10 and 27 mm (s3's four targets are all on one wall).
    EXPECT_LT(k.check.d3, 0.04) << k.name;
  }
  EXPECT_EQ(s.registered.size(), 60u);
  ASSERT_FALSE(s.chunked.pairs.empty());
  for (const ChunkPairConsistency& p : s.chunked.pairs) {
    std::printf("%s and %s: %zu points, median %.1f mm, 90%% %.1f mm\n", p.a.c_str(), p.b.c_str(), p.overlap,
                1e3 * p.median, 1e3 * p.p90);
    EXPECT_LT(p.median, 0.02);
  }
  const std::map<std::string, Eigen::Vector3d> centres = CentresByFile(ReadColmapModel(s.model_dir));
  double sum_sq = 0, worst = 0;
  for (const CampaignPhoto& p : campaign.photos) {
    const double e = (centres.at(p.name) + s.chunked.frame.origin - campaign.ToSurvey(p.camera.Center())).norm();
    sum_sq += e * e;
    worst = std::max(worst, e);
  }
  const double rms = std::sqrt(sum_sq / centres.size());
  std::printf("camera centres in the survey frame against the truth: RMS %.1f mm, worst %.1f mm\n", 1e3 * rms,
              1e3 * worst);
  const JointAdjustmentResult& j = s.chunked.joint;
  ASSERT_TRUE(j.ran) << j.reason;
  std::printf("adjusted as one: %zu links, %zu observations added, %zu refused; check RMSE %.1f mm\n", j.links,
              j.extended, j.links_rejected, 1e3 * j.check.d3);
  EXPECT_GT(j.links + j.extended, 100u);
  EXPECT_GE(j.check.count, 3);
  EXPECT_LT(j.check.d3, 0.008);
  EXPECT_EQ(ReadColmapModel(s.model_dir).cameras.size(), 1u);  // the one camera of the campaign
  EXPECT_LT(rms, 0.010);
  EXPECT_LT(worst, 0.030);
}

}  // namespace
}  // namespace candi::photogrammetry

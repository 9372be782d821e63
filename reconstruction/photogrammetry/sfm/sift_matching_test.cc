#include "reconstruction/photogrammetry/sfm/sift_matching.h"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>
#include <set>
#include <stdexcept>

#include "core/check.h"
#include "reconstruction/photogrammetry/color_correct.h"
#include "reconstruction/photogrammetry/georef/similarity_fit.h"
#include "reconstruction/photogrammetry/mvs/fusion.h"
#include "reconstruction/photogrammetry/mvs/patch_match.h"
#include "reconstruction/photogrammetry/registration/cleaning.h"
#include "reconstruction/photogrammetry/registration/registration.h"
#include "reconstruction/photogrammetry/scenes/synthetic_views.h"
#include "reconstruction/photogrammetry/sfm/colmap_database.h"
#include "reconstruction/photogrammetry/sfm/colmap_runner.h"
#include "tests/util/input_error.h"
#include "tests/util/option_check.h"
#include "tests/util/test_util.h"

namespace candi::photogrammetry {
namespace {

using candi::testing::ReadBytes;
using candi::testing::RunCommand;
using candi::testing::TempDir;
using candi::testing::WriteBytes;

// Random SIFT-like descriptors: non-negative bytes of L2 norm about 512, as COLMAP stores them.
std::vector<uint8_t> RandomDescriptors(int rows, std::mt19937* rng) {
  std::vector<uint8_t> d(static_cast<size_t>(rows) * 128);
  std::gamma_distribution<double> g(0.6, 1.0);
  for (int r = 0; r < rows; ++r) {
    std::vector<double> v(128);
    double norm = 0;
    for (double& x : v) {
      x = g(*rng);
      norm += x * x;
    }
    for (int c = 0; c < 128; ++c) d[r * 128 + c] = static_cast<uint8_t>(std::min(255.0, std::floor(512 * v[c] / std::sqrt(norm))));
  }
  return d;
}

// `source` with integer noise added (a re-observation of the same features).
std::vector<uint8_t> Perturbed(const std::vector<uint8_t>& source, int amplitude, std::mt19937* rng) {
  std::uniform_int_distribution<int> noise(-amplitude, amplitude);
  std::vector<uint8_t> out(source.size());
  for (size_t i = 0; i < source.size(); ++i) out[i] = static_cast<uint8_t>(std::clamp(source[i] + noise(*rng), 0, 255));
  return out;
}

// COLMAP 3.8's brute-force criterion written out literally (integer distance matrix, one way each,
// then the cross check), the reference for the blocked float version.
std::vector<std::pair<int, int>> Reference(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  const int na = static_cast<int>(a.size() / 128), nb = static_cast<int>(b.size() / 128);
  std::vector<int> dist(static_cast<size_t>(na) * nb);
  for (int i = 0; i < na; ++i)
    for (int j = 0; j < nb; ++j) {
      int s = 0;
      for (int c = 0; c < 128; ++c) s += a[i * 128 + c] * b[j * 128 + c];
      dist[static_cast<size_t>(i) * nb + j] = s;
    }
  auto one_way = [&](bool forward) {
    const int n = forward ? na : nb, m = forward ? nb : na;
    std::vector<int> match(n, -1);
    for (int i = 0; i < n; ++i) {
      int best_i = -1, best = 0, second = 0;
      for (int j = 0; j < m; ++j) {
        const int d = forward ? dist[static_cast<size_t>(i) * nb + j] : dist[static_cast<size_t>(j) * nb + i];
        if (d > best) { best_i = j; second = best; best = d; } else if (d > second) { second = d; }
      }
      if (best_i == -1) continue;
      const float kNorm = 1.0f / (512.0f * 512.0f);
      const float bn = std::acos(std::min(kNorm * best, 1.0f));
      if (bn > 0.7f) continue;
      const float sn = std::acos(std::min(kNorm * second, 1.0f));
      if (bn >= 0.8f * sn) continue;
      match[i] = best_i;
    }
    return match;
  };
  const std::vector<int> m12 = one_way(true), m21 = one_way(false);
  std::vector<std::pair<int, int>> out;
  for (int i = 0; i < na; ++i)
    if (m12[i] != -1 && m21[m12[i]] == i) out.emplace_back(i, m12[i]);
  return out;
}

TEST(MatchSiftBruteForce, EqualsColmapsCriterionExactly) {
  std::mt19937 rng(11);
  // More rows than one block (512), so the blocked column pass is exercised.
  const std::vector<uint8_t> a = RandomDescriptors(700, &rng);
  std::vector<uint8_t> b = Perturbed(a, 6, &rng);
  const std::vector<uint8_t> extra = RandomDescriptors(300, &rng);
  b.insert(b.end(), extra.begin(), extra.end());
  // Ties: descriptor 5 of b repeated as 701 (a tie for a's 5: best == second, rejected), and a's 9
  // repeated in a as row 698 (two equal rows of a: b's 9 finds the lower one first).
  std::copy(b.begin() + 5 * 128, b.begin() + 6 * 128, b.begin() + 701 * 128);
  std::vector<uint8_t> a2 = a;
  std::copy(a.begin() + 9 * 128, a.begin() + 10 * 128, a2.begin() + 698 * 128);
  const auto got = MatchSiftBruteForce(a2.data(), 700, b.data(), 1000, SiftMatchOptions{});
  const auto want = Reference(a2, b);
  EXPECT_EQ(got, want);
  EXPECT_GT(got.size(), 500u) << "the perturbed copies match themselves";
  for (const auto& [i, j] : got) EXPECT_NE(i, 5);
  for (const auto& [i, j] : got) EXPECT_TRUE(i != 9 && i != 698) << "a tie in b's direction fails the ratio test";
  size_t identity = 0;
  for (const auto& [i, j] : got) identity += i == j;
  EXPECT_EQ(identity, got.size()) << "every match is a planted one";
}

TEST(PhotogrammetryModuleOptions, DefaultsPassCheck) {
  testing::ExpectDefaultsPass<SiftMatchOptions, SfmOptions, PatchMatchOptions, FusionOptions,
                              CleanOptions, RegistrationOptions, SimilarityFitOptions,
                              ColorCorrectionOptions, SyntheticViewsOptions>();
}

TEST(SiftMatchOptions, BadValuesNameTheFieldAndTheMatchersCheckThem) {
  SiftMatchOptions o;
  o.max_ratio = 0;
  EXPECT_EQ(testing::OptionCheckMessage(o), "SiftMatchOptions::max_ratio = 0; must be > 0");
  o = {};
  o.max_distance = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(testing::OptionCheckMessage(o), "SiftMatchOptions::max_distance = nan; must be > 0");
  std::mt19937 rng(3);
  const std::vector<uint8_t> a = RandomDescriptors(4, &rng);
  EXPECT_THROW(MatchSiftBruteForce(a.data(), 4, a.data(), 4, o), std::invalid_argument);
  TempDir dir;
  DatabaseImage image;
  image.name = "a.png";
  EXPECT_THROW(WriteMatchList({image}, {}, o, 1, dir.File("m.txt")), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(dir.File("m.txt")));
}

TEST(MatchSiftBruteForce, EmptyAndZeroDescriptors) {
  std::mt19937 rng(3);
  const std::vector<uint8_t> a = RandomDescriptors(4, &rng);
  EXPECT_TRUE(MatchSiftBruteForce(a.data(), 4, nullptr, 0, SiftMatchOptions{}).empty());
  EXPECT_TRUE(MatchSiftBruteForce(nullptr, 0, a.data(), 4, SiftMatchOptions{}).empty());
  const std::vector<uint8_t> zeros(4 * 128, 0);  // no positive dot product: no best, no match
  EXPECT_TRUE(MatchSiftBruteForce(zeros.data(), 4, a.data(), 4, SiftMatchOptions{}).empty());
}

TEST(Pairs, ExhaustiveAndSequential) {
  EXPECT_EQ(ExhaustivePairs(3), (std::vector<std::pair<size_t, size_t>>{{0, 1}, {0, 2}, {1, 2}}));
  EXPECT_EQ(ExhaustivePairs(1).size(), 0u);
  EXPECT_EQ(ExhaustivePairs(50).size(), 1225u);
  EXPECT_EQ(SequentialPairs(4, 2), (std::vector<std::pair<size_t, size_t>>{{0, 1}, {0, 2}, {1, 2}, {1, 3}, {2, 3}}));
  EXPECT_EQ(SequentialPairs(3, 10).size(), 3u);
}

std::vector<DatabaseImage> Images(int count, std::mt19937* rng) {
  const std::vector<uint8_t> base = RandomDescriptors(300, rng);
  std::vector<DatabaseImage> images;
  for (int k = 0; k < count; ++k) {
    DatabaseImage im;
    im.image_id = k + 1;
    im.name = "p" + std::to_string(k) + ".jpg";
    im.descriptors = Perturbed(base, 8, rng);
    im.rows = 300;
    images.push_back(im);
  }
  return images;
}

TEST(WriteMatchList, SameBytesForAnyThreadCountInColmapsRawFormat) {
  std::mt19937 rng(5);
  const std::vector<DatabaseImage> images = Images(5, &rng);
  TempDir dir;
  size_t last_done = 0;
  const MatchListSummary one = WriteMatchList(images, ExhaustivePairs(5), SiftMatchOptions{}, 1, dir.File("m1.txt"),
                                              [&](size_t done, size_t total) {
                                                EXPECT_EQ(total, 10u);
                                                EXPECT_GT(done, last_done);
                                                last_done = done;
                                              });
  EXPECT_EQ(last_done, 10u);
  WriteMatchList(images, ExhaustivePairs(5), SiftMatchOptions{}, 2, dir.File("m2.txt"));
  const std::string text = ReadBytes(dir.File("m1.txt"));
  EXPECT_EQ(text, ReadBytes(dir.File("m2.txt")));
  EXPECT_EQ(one.pairs, 10u);
  EXPECT_EQ(one.pairs_written, 10u);
  EXPECT_GT(one.matches, 10u * 200);
  EXPECT_EQ(text.rfind("p0.jpg p1.jpg\n", 0), 0u) << text.substr(0, 40);
  // One blank line closes each pair.
  size_t blocks = 0;
  for (size_t at = text.find("\n\n"); at != std::string::npos; at = text.find("\n\n", at + 2)) ++blocks;
  EXPECT_EQ(blocks, 10u);
}

TEST(WriteMatchList, RefusesNamesWithWhitespaceAndKeepsTheOldFile) {
  std::mt19937 rng(6);
  std::vector<DatabaseImage> images = Images(2, &rng);
  images[1].name = "my photo.jpg";
  TempDir dir;
  WriteBytes(dir.File("m.txt"), "old");
  try {
    WriteMatchList(images, ExhaustivePairs(2), SiftMatchOptions{}, 1, dir.File("m.txt"));
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("my photo.jpg"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("whitespace"), std::string::npos) << e.what();
  }
  EXPECT_EQ(ReadBytes(dir.File("m.txt")), "old");
}

TEST(ClearBorderDescriptors, ClearsTheOutermostPixelsOnly) {
  DatabaseImage im;
  im.width = 100, im.height = 80, im.rows = 5;
  im.xy = {0.5f, 40, 50, 79.5f, 50, 40, 99.2f, 10, 98.9f, 79.0f};
  im.descriptors.assign(5 * 128, 7);
  std::vector<DatabaseImage> images = {im};
  EXPECT_EQ(ClearBorderDescriptors(&images), 3u);
  const auto row_sum = [&](int r) {
    int s = 0;
    for (int c = 0; c < 128; ++c) s += images[0].descriptors[r * 128 + c];
    return s;
  };
  EXPECT_EQ(row_sum(0), 0);
  EXPECT_EQ(row_sum(1), 0);
  EXPECT_EQ(row_sum(2), 7 * 128);
  EXPECT_EQ(row_sum(3), 0);
  EXPECT_EQ(row_sum(4), 7 * 128) << "(98.9, 79.0) is inside the last pixel's centre line";
}

// With scales, the bottom rows and right columns VLFeat leaves without a descriptor at a
// keypoint's octave: within 1 + 1.2 sigma of the bottom, 1 + 0.4 sigma of the right edge.
TEST(ClearBorderDescriptors, ClearsWhatTheKeypointsOctaveLeavesUnwritten) {
  DatabaseImage im;
  im.width = 320, im.height = 240, im.rows = 6;
  // (x, y, sigma): the campaign's three that differed between thread counts, and their neighbours.
  im.xy = {179.29f, 238.45f, 226.02f, 236.05f, 226.02f, 236.05f, 100, 230, 317.5f, 100, 315, 100};
  im.scale = {1.0f, 4.0f, 1.5f, 8.0f, 5.0f, 5.0f};
  im.descriptors.assign(6 * 128, 7);
  std::vector<DatabaseImage> images = {im};
  EXPECT_EQ(ClearBorderDescriptors(&images), 4u);
  std::vector<bool> cleared;
  for (int r = 0; r < 6; ++r) cleared.push_back(images[0].descriptors[r * 128] == 0);
  EXPECT_EQ(cleared, (std::vector<bool>{true, true, false, true, true, false}));
}

std::string ErrorOf(const std::string& path) {
  return testing::InputErrorMessage([&] { ReadColmapDescriptors(path); });
}

TEST(ReadColmapDescriptors, MissingAndNonDatabaseFilesAreNamed) {
  TempDir dir;
  EXPECT_NE(ErrorOf(dir.File("none.db")).find("none.db"), std::string::npos);
  WriteBytes(dir.File("text.db"), "this is not an SQLite file, only some text that is long enough");
  const std::string e = ErrorOf(dir.File("text.db"));
  EXPECT_NE(e.find("text.db"), std::string::npos) << e;
}

// Two w x h PGMs v0, v1 of one textured pattern, the second shifted by 5 px, with a little noise
// (features to extract and to match).
void WriteShiftedPatterns(const std::string& folder, int w, int h, unsigned seed) {
  std::filesystem::create_directories(folder);
  std::mt19937 rng(seed);
  for (int k = 0; k < 2; ++k) {
    std::string pgm = "P5 " + std::to_string(w) + " " + std::to_string(h) + " 255\n";
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) pgm.push_back(static_cast<char>((((x + 5 * k) / 6 * 37 + y / 6 * 91) % 251) ^ (rng() & 15)));
    WriteBytes(folder + "/v" + std::to_string(k) + ".pgm", pgm);
  }
}

// A database written by the installed COLMAP: the images by id with their descriptors.
TEST(ReadColmapDescriptors, ReadsColmapsOwnDatabase) {
  if (RunCommand("colmap help").code != 0) GTEST_SKIP() << "COLMAP is not installed here (Debian: apt install colmap)";
  TempDir dir;
  WriteShiftedPatterns(dir.File("img"), 200, 150, 9);
  const auto r = RunCommand("colmap feature_extractor --database_path " + dir.File("d.db") + " --image_path " +
                            dir.File("img") + " --SiftExtraction.use_gpu 0 --SiftExtraction.num_threads 1 2>&1");
  ASSERT_EQ(r.code, 0) << r.output;
  const std::vector<DatabaseImage> images = ReadColmapDescriptors(dir.File("d.db"));
  ASSERT_EQ(images.size(), 2u);
  EXPECT_EQ(images[0].name, "v0.pgm");
  EXPECT_EQ(images[1].name, "v1.pgm");
  EXPECT_LT(images[0].image_id, images[1].image_id);
  for (const DatabaseImage& im : images) {
    EXPECT_GT(im.rows, 20) << im.name;
    EXPECT_EQ(im.width, 200);
    EXPECT_EQ(im.height, 150);
    ASSERT_EQ(im.xy.size(), static_cast<size_t>(2 * im.rows));
    for (int64_t r = 0; r < im.rows; ++r) {
      EXPECT_TRUE(im.xy[2 * r] >= 0 && im.xy[2 * r] <= 200 && im.xy[2 * r + 1] >= 0 && im.xy[2 * r + 1] <= 150);
    }
    EXPECT_EQ(im.descriptors.size(), static_cast<size_t>(im.rows) * 128);
    double norm = 0;
    for (int c = 0; c < 128; ++c) norm += double(im.descriptors[c]) * im.descriptors[c];
    EXPECT_NEAR(std::sqrt(norm), 512, 40) << "COLMAP's descriptors have length ~512";
  }
  // Renumbered by name (here already in order: nothing to do), and refused once matched.
  EXPECT_FALSE(RenumberImagesByName(dir.File("d.db")));
  // The shifted copies match each other.
  EXPECT_GT(MatchSiftBruteForce(images[0].descriptors.data(), images[0].rows, images[1].descriptors.data(),
                                images[1].rows, SiftMatchOptions{}).size(), 10u);
}

// Images named in the reverse order of extraction get ids by name, cameras by first use; the
// descriptors follow their image.
TEST(RenumberImagesByName, IdsFollowNamesAndDataFollowsIds) {
  if (RunCommand("colmap help").code != 0) GTEST_SKIP() << "COLMAP is not installed here (Debian: apt install colmap)";
  TempDir dir;
  std::mt19937 rng(4);
  for (int k = 0; k < 3; ++k) {
    std::filesystem::create_directories(dir.File("img" + std::to_string(k)));
    std::string pgm = "P5 120 90 255\n";
    for (int i = 0; i < 120 * 90; ++i) pgm.push_back(static_cast<char>(rng() & 255));
    // Extracted in the order z, m, a (one run per image, separate cameras).
    WriteBytes(dir.File("img" + std::to_string(k) + "/" + std::string(1, "zma"[k]) + ".pgm"), pgm);
    const auto r = RunCommand("colmap feature_extractor --database_path " + dir.File("d.db") + " --image_path " +
                              dir.File("img" + std::to_string(k)) + " --SiftExtraction.use_gpu 0 2>&1");
    ASSERT_EQ(r.code, 0) << r.output;
  }
  const std::vector<DatabaseImage> before = ReadColmapDescriptors(dir.File("d.db"));
  ASSERT_EQ(before.size(), 3u);
  ASSERT_EQ(before[0].name, "z.pgm");
  EXPECT_TRUE(RenumberImagesByName(dir.File("d.db")));
  const std::vector<DatabaseImage> after = ReadColmapDescriptors(dir.File("d.db"));
  ASSERT_EQ(after.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(after[k].image_id, k + 1);
    EXPECT_EQ(after[k].name, before[2 - k].name);
    EXPECT_EQ(after[k].descriptors, before[2 - k].descriptors) << after[k].name;
  }
  EXPECT_FALSE(RenumberImagesByName(dir.File("d.db"))) << "a second call has nothing to do";
  // Cameras (one per extraction run): numbered by their first image, so a.pgm's is camera 1.
  EXPECT_EQ(before[2].camera_id, 3);
  for (int k = 0; k < 3; ++k) EXPECT_EQ(after[k].camera_id, k + 1) << after[k].name;
}

// DIR/d.db: two shifted patterns extracted and matched by the installed COLMAP; false on a failure.
bool WriteMatchedDatabase(const TempDir& dir) {
  WriteShiftedPatterns(dir.File("img"), 160, 120, 8);
  return RunCommand("colmap feature_extractor --database_path " + dir.File("d.db") + " --image_path " + dir.File("img") +
                    " --SiftExtraction.use_gpu 0 >/dev/null 2>&1").code == 0 &&
         RunCommand("colmap exhaustive_matcher --database_path " + dir.File("d.db") +
                    " --SiftMatching.use_gpu 0 >/dev/null 2>&1").code == 0;
}

TEST(RenumberImagesByName, RefusesADatabaseWithMatches) {
  if (RunCommand("colmap help").code != 0) GTEST_SKIP() << "COLMAP is not installed here (Debian: apt install colmap)";
  TempDir dir;
  ASSERT_TRUE(WriteMatchedDatabase(dir));
  try {
    RenumberImagesByName(dir.File("d.db"));
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("holds matches already"), std::string::npos) << e.what();
  }
}

// The pairs matched and verified, read back by name; removed by name in either order; a
// verification blob that does not hold its rows is refused, naming the pair.
TEST(ColmapDatabase, MatchedPairsAreReadAndRemovedByName) {
  if (RunCommand("colmap help").code != 0) GTEST_SKIP() << "COLMAP is not installed here (Debian: apt install colmap)";
  TempDir dir;
  ASSERT_TRUE(WriteMatchedDatabase(dir));
  const std::set<std::pair<std::string, std::string>> one = {{"v0.pgm", "v1.pgm"}};
  EXPECT_EQ(MatchedPairNames(dir.File("d.db")), one);
  ASSERT_EQ(VerifiedPairNames(dir.File("d.db")), one);
  const std::vector<PairMatches> inliers = ReadVerifiedMatches(dir.File("d.db"));
  ASSERT_EQ(inliers.size(), 1u);
  EXPECT_GT(inliers[0].matches.size(), 10u);
  EXPECT_TRUE(ReadVerifiedMatches(dir.File("d.db"), [](const std::string&, const std::string&) { return false; }).empty());
  // A blob shorter than its rows.
  std::filesystem::copy_file(dir.File("d.db"), dir.File("bad.db"));
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(dir.File("bad.db").c_str(), &db), SQLITE_OK);
    ASSERT_EQ(sqlite3_exec(db, "UPDATE two_view_geometries SET rows = rows + 1", nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(db);
  }
  const std::string e = testing::InputErrorMessage([&] { ReadVerifiedMatches(dir.File("bad.db")); });
  EXPECT_NE(e.find("bad.db"), std::string::npos) << e;
  EXPECT_NE(e.find("inliers in a blob of"), std::string::npos) << e;
  // Removed by name (the other order, and a pair the database does not hold, passed over).
  RemoveMatches(dir.File("d.db"), {{"v1.pgm", "v0.pgm"}, {"v0.pgm", "none.pgm"}});
  EXPECT_TRUE(MatchedPairNames(dir.File("d.db")).empty());
  EXPECT_EQ(CountVerifiedPairs(dir.File("d.db")), 0u);
  EXPECT_EQ(ReadColmapDescriptors(dir.File("d.db")).size(), 2u) << "the images stay";
}

}  // namespace
}  // namespace candi::photogrammetry

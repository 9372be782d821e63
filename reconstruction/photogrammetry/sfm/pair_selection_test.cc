#include "reconstruction/photogrammetry/sfm/pair_selection.h"

#include <tbb/global_control.h>

#include <set>
#include <stdexcept>

#include <gtest/gtest.h>

#include "core/check.h"
#include "core/rng.h"
#include "tests/util/test_util.h"

namespace candi::photogrammetry {
namespace {

using candi::testing::TempDir;
using candi::testing::WriteBytes;

// A walk of `n` images where image i shows "places" i .. i + 3 (each place a fixed set of 60
// descriptors, drawn around its own centre), so image i overlaps i - 3 .. i + 3 and nothing else;
// with `loop`, the last places are the first ones again (the walk returns to its start).
std::vector<DatabaseImage> Walk(int n, bool loop, uint64_t seed) {
  const int places = loop ? n : n + 3;
  std::vector<std::vector<uint8_t>> place(places);
  Rng rng(seed);
  for (int p = 0; p < places; ++p) {
    std::vector<double> centre(128);
    for (double& c : centre) c = rng.Uniform() * 200;
    for (int k = 0; k < 60; ++k)
      for (int d = 0; d < 128; ++d)
        place[p].push_back(static_cast<uint8_t>(std::clamp(centre[d] + 12 * rng.Normal(), 0.0, 255.0)));
  }
  std::vector<DatabaseImage> images(n);
  for (int i = 0; i < n; ++i) {
    char name[32];
    std::snprintf(name, sizeof(name), "walk_%04d.jpg", i);
    images[i].name = name;
    images[i].image_id = i + 1;
    for (int q = 0; q < 4; ++q) {
      const auto& d = place[(i + q) % places];
      images[i].descriptors.insert(images[i].descriptors.end(), d.begin(), d.end());
    }
    images[i].rows = static_cast<int64_t>(images[i].descriptors.size() / 128);
  }
  return images;
}

PairSelectionOptions SmallTree() {
  PairSelectionOptions o;
  o.branching = 8;
  o.depth = 3;
  o.train_descriptors = 20000;
  o.kmeans_iterations = 5;
  return o;
}

TEST(PairSelection, StrategiesParseAndBadOptionsNameTheField) {
  for (PairStrategy s : {PairStrategy::kAuto, PairStrategy::kExhaustive, PairStrategy::kSequential,
                         PairStrategy::kRetrieval, PairStrategy::kPositional}) {
    EXPECT_EQ(ParsePairStrategy(PairStrategyName(s)), s);
  }
  EXPECT_THROW(ParsePairStrategy("vocab"), std::invalid_argument);
  PairSelectionOptions o;
  o.depth = 9;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = PairSelectionOptions();
  o.branching = 64;
  o.depth = 5;  // 10^9 leaves
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

TEST(PairSelection, RetrievalFindsTheOverlappingImagesTheSameOnAnyThreadCount) {
  const std::vector<DatabaseImage> images = Walk(40, false, 3);
  std::vector<std::vector<std::pair<size_t, double>>> found[2];
  for (int threads : {1, 2}) {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
    const VocabularyTree tree = TrainVocabularyTree(images, SmallTree());
    EXPECT_EQ(tree.Leaves(), 512);
    found[threads - 1] = RetrieveNeighbours(tree, images, 4);
  }
  EXPECT_EQ(found[0], found[1]);
  // Image i's 4 most similar are among its true overlaps i - 3 .. i + 3, the nearest first.
  int in_overlap = 0, total = 0;
  for (size_t i = 0; i < images.size(); ++i) {
    // The walk's ends overlap three images only.
    ASSERT_EQ(found[0][i].size(), i == 0 || i + 1 == images.size() ? 3u : 4u) << i;
    for (const auto& [j, score] : found[0][i]) {
      ++total;
      in_overlap += j != i && (j > i ? j - i : i - j) <= 3;
    }
    const size_t best = found[0][i][0].first;
    EXPECT_EQ(best > i ? best - i : i - best, 1u) << i;
  }
  EXPECT_EQ(in_overlap, total);
}

TEST(PairSelection, AutoIsExhaustiveForFewAndGrowsLinearlyBeyond) {
  PairSelectionOptions o = SmallTree();
  o.exhaustive_max_images = 30;
  o.sequential_overlap = 3;
  o.retrieval_neighbours = 5;
  const PairSelection few = SelectPairs(Walk(30, false, 1), {}, o);
  EXPECT_EQ(few.strategy, "exhaustive");
  EXPECT_EQ(few.pairs.size(), 30u * 29 / 2);
  for (int n : {60, 120}) {
    const PairSelection many = SelectPairs(Walk(n, true, 1), {}, o);
    EXPECT_NE(many.strategy.find("sequential 3 + retrieval 5"), std::string::npos) << many.strategy;
    EXPECT_LE(many.pairs.size(), static_cast<size_t>(n) * (3 + 5));
    EXPECT_GE(many.pairs.size(), static_cast<size_t>(n) * 3 - 6);
    EXPECT_TRUE(std::is_sorted(many.pairs.begin(), many.pairs.end()));
    // The loop closes: the last images are paired with the first by retrieval, not by sequence.
    bool closed = false;
    for (const auto& [i, j] : many.pairs) closed |= i <= 1 && j >= static_cast<size_t>(n) - 2;
    EXPECT_TRUE(closed) << n;
  }
  // Asked for by name, sequential is the sequence alone: the loop stays open.
  o.strategy = PairStrategy::kSequential;
  const PairSelection sequence = SelectPairs(Walk(60, true, 1), {}, o);
  EXPECT_EQ(sequence.strategy, "sequential 3");
  EXPECT_EQ(sequence.retrieval, 0u);
  EXPECT_EQ(sequence.pairs.size(), 60u * 3 - 6);
  for (const auto& [i, j] : sequence.pairs) EXPECT_LE(j - i, 3u);
}

TEST(PairSelection, PositionsPairEachPhotoWithItsNearest) {
  std::vector<DatabaseImage> images = Walk(12, false, 2);
  std::map<std::string, Eigen::Vector3d> positions;
  for (size_t i = 0; i < images.size(); ++i) positions[images[i].name] = Eigen::Vector3d(3.0 * i, 0, 0);
  PairSelectionOptions o;
  o.strategy = PairStrategy::kPositional;
  o.position_neighbours = 2;
  const PairSelection s = SelectPairs(images, positions, o);
  EXPECT_EQ(s.retrieval, 0u);
  const std::set<std::pair<size_t, size_t>> pairs(s.pairs.begin(), s.pairs.end());
  for (size_t i = 0; i + 1 < images.size(); ++i) EXPECT_TRUE(pairs.count({i, i + 1})) << i;
  EXPECT_TRUE(pairs.count({0, 2}));  // the ends' second nearest is two along
  for (const auto& [i, j] : s.pairs) EXPECT_LE(j - i, 2u);
  // Without priors, positional matching proposes nothing.
  EXPECT_TRUE(SelectPairs(images, {}, o).pairs.empty());
}

TEST(PairSelection, TransitivePairsJoinPhotosThatShareVerifiedNeighbours) {
  // Two rows of photos: 0-1-2-3 along the lower row, 4-5-6-7 along the upper; each upper photo
  // verified with the lower one below it, and the rows' sequence pairs tried and verified. The
  // diagonals (0-5, 1-4, ...) were never tried: each shares two verified neighbours.
  std::vector<std::pair<size_t, size_t>> verified = {{0, 1}, {1, 2}, {2, 3}, {4, 5}, {5, 6}, {6, 7},
                                                     {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  std::set<std::pair<size_t, size_t>> tried(verified.begin(), verified.end());
  tried.insert({0, 2});  // tried and refused: never proposed again
  const auto all = TransitivePairs(8, verified, tried, 100);
  const std::set<std::pair<size_t, size_t>> got(all.begin(), all.end());
  EXPECT_EQ(got.size(), all.size());
  for (const auto& p : all) {
    EXPECT_LT(p.first, p.second);
    EXPECT_FALSE(tried.count(p)) << p.first << "-" << p.second;
  }
  for (const std::pair<size_t, size_t>& diagonal : {std::pair<size_t, size_t>{0, 5}, {1, 4}, {1, 6}, {2, 5}, {2, 7}, {3, 6}})
    EXPECT_TRUE(got.count(diagonal)) << diagonal.first << "-" << diagonal.second;
  EXPECT_TRUE(got.count({1, 3}));   // two along the row, through 2
  EXPECT_FALSE(got.count({0, 2}));  // tried
  EXPECT_FALSE(got.count({0, 3}));  // three steps
  EXPECT_FALSE(got.count({0, 6}));
  // One a photo: each proposes its candidate with the most shared neighbours (the diagonals share
  // two; 1-3 shares one), ties to the lower index.
  const auto one = TransitivePairs(8, verified, tried, 1);
  EXPECT_LE(one.size(), 8u);
  const std::set<std::pair<size_t, size_t>> best(one.begin(), one.end());
  EXPECT_TRUE(best.count({0, 5}));  // 0's only candidate with two
  EXPECT_TRUE(best.count({1, 4}));  // 1: 4 and 6 share two; 4 is lower
  EXPECT_FALSE(best.count({1, 3}));
  // Nothing verified, nothing proposed; a pair naming an image beyond n is a misuse.
  EXPECT_TRUE(TransitivePairs(8, {}, {}, 5).empty());
  EXPECT_THROW(TransitivePairs(4, verified, tried, 5), InternalError);
  EXPECT_THROW(TransitivePairs(8, verified, tried, 0), InternalError);
  PairSelectionOptions o;
  o.transitive_rounds = -1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

TEST(PairSelection, PriorsFileErrorsNameTheLineAndField) {
  TempDir dir;
  const auto error = [&](const std::string& text) {
    WriteBytes(dir.File("p.csv"), text);
    try {
      ReadPositionPriors(dir.File("p.csv"));
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  WriteBytes(dir.File("ok.csv"), "# priors\nname,E,N,H,sigma\na.jpg,410000.5,9159000.25,265,3\nb.jpg,1,2,3,3\n");
  const auto priors = ReadPositionPriors(dir.File("ok.csv"));
  ASSERT_EQ(priors.size(), 2u);
  EXPECT_DOUBLE_EQ(priors.at("a.jpg").x(), 410000.5);
  EXPECT_NE(error("name,E,N\na,1,2\n").find("lacks the column 'H'"), std::string::npos);
  EXPECT_NE(error("name,E,N,H\na,1,x,3\n").find("line 2: field 'N'"), std::string::npos);
  EXPECT_NE(error("name,E,N,H\na,1,nan,3\n").find("field 'N'"), std::string::npos);
  EXPECT_NE(error("name,E,N,H\na,1,2,3\na,4,5,6\n").find("line 3: field 'name': 'a' given twice"),
            std::string::npos);
  EXPECT_NE(error("name,E,N,H\na,1,2\n").find("line 2: 3 fields; the header has 4"), std::string::npos);
  EXPECT_NE(error("name,E,N,H\n,1,2,3\n").find("field 'name': empty"), std::string::npos);
  EXPECT_THROW(ReadPositionPriors(dir.File("absent.csv")), InputError);
}

}  // namespace
}  // namespace candi::photogrammetry

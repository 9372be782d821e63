#include "reconstruction/photogrammetry/sfm/sift_matching.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <Eigen/Core>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/atomic_file.h"
#include "core/check.h"

namespace candi::photogrammetry {

namespace {

constexpr int64_t kDimensions = 128;
constexpr int64_t kBlockRows = 512;  // rows of `a` per distance block (512 x rows_b floats)

using Matrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Rows [begin, end) of a row-major descriptor array, as floats.
Matrix ToFloat(const uint8_t* data, int64_t begin, int64_t end) {
  Matrix m(end - begin, kDimensions);
  const uint8_t* p = data + begin * kDimensions;
  for (int64_t i = 0; i < (end - begin) * kDimensions; ++i) m.data()[i] = static_cast<float>(p[i]);
  return m;
}

// The best and second-best dot product found so far for one descriptor.
struct Best {
  int index = -1;
  int best = 0;
  int second = 0;
  void Offer(int dot, int i) {
    if (dot > best) {
      index = i;
      second = best;
      best = dot;
    } else if (dot > second) {
      second = dot;
    }
  }
};

// COLMAP's test of a best / second-best pair (sift.cc, FindBestMatchesOneWayBruteForce).
bool Passes(const Best& b, const SiftMatchOptions& o) {
  if (b.index < 0) return false;
  constexpr float kNorm = 1.0f / (512.0f * 512.0f);
  const float best_angle = std::acos(std::min(kNorm * static_cast<float>(b.best), 1.0f));
  if (best_angle > o.max_distance) return false;
  const float second_angle = std::acos(std::min(kNorm * static_cast<float>(b.second), 1.0f));
  return best_angle < o.max_ratio * second_angle;
}

bool HasWhitespace(const std::string& s) {
  return std::any_of(s.begin(), s.end(), [](unsigned char c) { return std::isspace(c) != 0; });
}

}  // namespace

void SiftMatchOptions::Check() const {
  // As COLMAP's SiftMatchingOptions::Check(). NaN fails: it would refuse every match.
  CANDI_CHECK_OPTION_GT(max_ratio, 0);
  CANDI_CHECK_OPTION_GT(max_distance, 0);
}

std::vector<std::pair<int, int>> MatchSiftBruteForce(const uint8_t* a, int64_t rows_a, const uint8_t* b,
                                                     int64_t rows_b, const SiftMatchOptions& options) {
  options.Check();
  CANDI_CHECK(rows_a >= 0 && rows_b >= 0);
  CANDI_CHECK(rows_a < (int64_t{1} << 31) && rows_b < (int64_t{1} << 31));
  std::vector<std::pair<int, int>> matches;
  if (rows_a == 0 || rows_b == 0) return matches;
  const Matrix fb = ToFloat(b, 0, rows_b);
  std::vector<Best> best_ab(static_cast<size_t>(rows_a)), best_ba(static_cast<size_t>(rows_b));
  Matrix dots;
  // Blocks of a's rows in increasing order, so every descriptor of b meets a's rows in index
  // order and its ties resolve as in one pass. Each dot product is an integer <= 128 x 255^2 <
  // 2^24: exact in float, whatever order Eigen sums in.
  for (int64_t begin = 0; begin < rows_a; begin += kBlockRows) {
    const int64_t end = std::min(rows_a, begin + kBlockRows);
    dots.noalias() = ToFloat(a, begin, end) * fb.transpose();
    for (int64_t r = 0; r < end - begin; ++r) {
      Best& row = best_ab[static_cast<size_t>(begin + r)];
      for (int64_t c = 0; c < rows_b; ++c) {
        const int dot = static_cast<int>(dots(r, c));
        row.Offer(dot, static_cast<int>(c));
        best_ba[static_cast<size_t>(c)].Offer(dot, static_cast<int>(begin + r));
      }
    }
  }
  for (int64_t i = 0; i < rows_a; ++i) {
    const Best& forward = best_ab[static_cast<size_t>(i)];
    if (!Passes(forward, options)) continue;
    if (options.cross_check) {
      const Best& backward = best_ba[static_cast<size_t>(forward.index)];
      if (!Passes(backward, options) || backward.index != i) continue;
    }
    matches.emplace_back(static_cast<int>(i), forward.index);
  }
  return matches;
}

std::vector<std::pair<size_t, size_t>> ExhaustivePairs(size_t count) {
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t i = 0; i < count; ++i)
    for (size_t j = i + 1; j < count; ++j) pairs.emplace_back(i, j);
  return pairs;
}

std::vector<std::pair<size_t, size_t>> SequentialPairs(size_t count, int overlap) {
  CANDI_CHECK(overlap >= 1);
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t i = 0; i < count; ++i)
    for (size_t j = i + 1; j < count && j <= i + static_cast<size_t>(overlap); ++j) pairs.emplace_back(i, j);
  return pairs;
}

size_t ClearBorderDescriptors(std::vector<DatabaseImage>* images, double margin) {
  size_t cleared = 0;
  for (DatabaseImage& image : *images) {
    CANDI_CHECK(image.xy.size() == static_cast<size_t>(2 * image.rows));
    const bool scaled = image.scale.size() == static_cast<size_t>(image.rows);
    for (int64_t r = 0; r < image.rows; ++r) {
      const double x = image.xy[2 * r], y = image.xy[2 * r + 1], sigma = scaled ? image.scale[r] : 0.0;
      if (x >= margin && y >= margin && x <= image.width - margin - kBorderColumnsPerSigma * sigma &&
          y <= image.height - margin - kBorderRowsPerSigma * sigma) {
        continue;
      }
      std::fill_n(image.descriptors.begin() + r * kDimensions, kDimensions, uint8_t{0});
      ++cleared;
    }
  }
  return cleared;
}

MatchListSummary WriteMatchList(const std::vector<DatabaseImage>& images,
                                const std::vector<std::pair<size_t, size_t>>& pairs,
                                const SiftMatchOptions& options, int threads, const std::string& path,
                                const std::function<void(size_t, size_t)>& progress) {
  options.Check();
  for (const DatabaseImage& image : images) {
    if (image.name.empty() || HasWhitespace(image.name)) {
      throw InputError(image.name, "", "a photo name with whitespace (or none) cannot go into COLMAP's "
                                       "match list, which is split on whitespace; rename the photo");
    }
  }
  for (const auto& [i, j] : pairs) CANDI_CHECK(i < images.size() && j < images.size() && i != j);
  std::vector<std::vector<std::pair<int, int>>> results(pairs.size());
  const int concurrency = threads > 0 ? threads : tbb::this_task_arena::max_concurrency();
  tbb::task_arena arena(concurrency);
  // Batches, so that progress is reported from this thread; each pair's result has its own slot.
  const size_t batch = static_cast<size_t>(std::max(1, 4 * concurrency));
  for (size_t begin = 0; begin < pairs.size(); begin += batch) {
    const size_t end = std::min(pairs.size(), begin + batch);
    arena.execute([&] {
      tbb::parallel_for(begin, end, [&](size_t k) {
        const DatabaseImage& a = images[pairs[k].first];
        const DatabaseImage& b = images[pairs[k].second];
        results[k] = MatchSiftBruteForce(a.descriptors.data(), a.rows, b.descriptors.data(), b.rows, options);
      });
    });
    if (progress) progress(end, pairs.size());
  }
  MatchListSummary summary;
  summary.pairs = pairs.size();
  std::string text;
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (results[k].empty()) continue;
    ++summary.pairs_written;
    summary.matches += results[k].size();
    text += images[pairs[k].first].name + " " + images[pairs[k].second].name + "\n";
    for (const auto& [i, j] : results[k]) text += std::to_string(i) + " " + std::to_string(j) + "\n";
    text += "\n";
  }
  WriteFileAtomic(path, text);
  return summary;
}

std::set<std::pair<std::string, std::string>> MatchListPairs(const std::string& path) {
  std::set<std::pair<std::string, std::string>> pairs;
  std::ifstream in(path);
  std::string line;
  bool header = true;  // blocks end with an empty line
  while (std::getline(in, line)) {
    if (line.empty()) {
      header = true;
      continue;
    }
    if (header) {
      std::istringstream fields(line);
      std::string a, b;
      if (fields >> a >> b) pairs.insert(b < a ? std::make_pair(b, a) : std::make_pair(a, b));
    }
    header = false;
  }
  return pairs;
}

}  // namespace candi::photogrammetry

#include "reconstruction/photogrammetry/sfm/pair_selection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

#include "core/check.h"
#include "core/parallel.h"
#include "core/rng.h"
#include "io/csv_table.h"

namespace candi::photogrammetry {

namespace {

constexpr int kDims = 128;

float SquaredDistance(const float* a, const float* b) {
  float s = 0;
  for (int d = 0; d < kDims; ++d) {
    const float t = a[d] - b[d];
    s += t * t;
  }
  return s;
}
float SquaredDistance(const uint8_t* a, const float* b) {
  float s = 0;
  for (int d = 0; d < kDims; ++d) {
    const float t = static_cast<float>(a[d]) - b[d];
    s += t * t;
  }
  return s;
}

// The nearest of k centres (k x 128), ties to the lower index.
template <typename T>
int Nearest(const T* x, const std::vector<float>& centres, int k) {
  int best = 0;
  float best_d = std::numeric_limits<float>::infinity();
  for (int c = 0; c < k; ++c) {
    const float d = SquaredDistance(x, centres.data() + static_cast<size_t>(c) * kDims);
    if (d < best_d) best_d = d, best = c;
  }
  return best;
}

// k-means of the rows `members` of `data` into k centres: k-means++ seeding, then Lloyd
// iterations (assignments in parallel, sums in member order: the same centres on any thread
// count). Fewer members than k: the members themselves, the last repeated.
std::vector<float> KMeans(const std::vector<float>& data, const std::vector<uint32_t>& members, int k,
                          int iterations, uint64_t seed, std::vector<int>* assignment) {
  std::vector<float> centres(static_cast<size_t>(k) * kDims);
  const size_t n = members.size();
  const auto row = [&](size_t i) { return data.data() + static_cast<size_t>(members[i]) * kDims; };
  if (n <= static_cast<size_t>(k)) {
    for (int c = 0; c < k; ++c) std::copy(row(std::min<size_t>(c, n - 1)), row(std::min<size_t>(c, n - 1)) + kDims,
                                          centres.begin() + static_cast<size_t>(c) * kDims);
    assignment->resize(n);
    for (size_t i = 0; i < n; ++i) (*assignment)[i] = static_cast<int>(i);
    return centres;
  }
  Rng rng(seed);
  std::vector<float> nearest(n, std::numeric_limits<float>::infinity());
  size_t pick = static_cast<size_t>(rng.Next() % n);
  for (int c = 0; c < k; ++c) {
    std::copy(row(pick), row(pick) + kDims, centres.begin() + static_cast<size_t>(c) * kDims);
    if (c + 1 == k) break;
    double total = 0;
    for (size_t i = 0; i < n; ++i) {
      nearest[i] = std::min(nearest[i], SquaredDistance(row(i), centres.data() + static_cast<size_t>(c) * kDims));
      total += nearest[i];
    }
    if (!(total > 0)) {  // every member sits on a centre: the remaining centres repeat it
      pick = 0;
      continue;
    }
    double target = rng.Uniform() * total;
    pick = n - 1;
    for (size_t i = 0; i < n; ++i) {
      target -= nearest[i];
      if (target < 0) {
        pick = i;
        break;
      }
    }
  }
  assignment->assign(n, 0);
  for (int it = 0; it < iterations; ++it) {
    ParallelFor(size_t{0}, n, [&](size_t i) { (*assignment)[i] = Nearest(row(i), centres, k); });
    if (it + 1 == iterations) break;
    std::vector<double> sums(static_cast<size_t>(k) * kDims, 0.0);
    std::vector<size_t> counts(k, 0);
    for (size_t i = 0; i < n; ++i) {
      const int c = (*assignment)[i];
      ++counts[c];
      const float* x = row(i);
      for (int d = 0; d < kDims; ++d) sums[static_cast<size_t>(c) * kDims + d] += x[d];
    }
    for (int c = 0; c < k; ++c) {
      if (counts[c] == 0) continue;  // an empty cluster keeps its centre
      for (int d = 0; d < kDims; ++d)
        centres[static_cast<size_t>(c) * kDims + d] = static_cast<float>(sums[static_cast<size_t>(c) * kDims + d] / counts[c]);
    }
  }
  return centres;
}

void AddPair(size_t a, size_t b, std::set<std::pair<size_t, size_t>>* pairs) {
  if (a != b) pairs->insert({std::min(a, b), std::max(a, b)});
}

}  // namespace

std::string PairStrategyName(PairStrategy strategy) {
  switch (strategy) {
    case PairStrategy::kAuto: return "auto";
    case PairStrategy::kExhaustive: return "exhaustive";
    case PairStrategy::kSequential: return "sequential";
    case PairStrategy::kRetrieval: return "retrieval";
    case PairStrategy::kPositional: return "positional";
  }
  return "?";
}

PairStrategy ParsePairStrategy(const std::string& name) {
  for (PairStrategy s : {PairStrategy::kAuto, PairStrategy::kExhaustive, PairStrategy::kSequential,
                         PairStrategy::kRetrieval, PairStrategy::kPositional}) {
    if (PairStrategyName(s) == name) return s;
  }
  throw std::invalid_argument("matching '" + name + "': expected auto, exhaustive, sequential, retrieval or positional");
}

void PairSelectionOptions::Check() const {
  CANDI_CHECK_OPTION_GE(exhaustive_max_images, 2);
  CANDI_CHECK_OPTION_GE(sequential_overlap, 0);
  CANDI_CHECK_OPTION_GE(retrieval_neighbours, 0);
  CANDI_CHECK_OPTION_GE(position_neighbours, 0);
  CANDI_CHECK_OPTION_GE(transitive_rounds, 0);
  CANDI_CHECK_OPTION_GE(transitive_neighbours, 1);
  CANDI_CHECK_OPTION_IN(branching, 2, 64);
  CANDI_CHECK_OPTION_IN(depth, 1, 8);
  CANDI_CHECK_OPTION(std::pow(static_cast<double>(branching), depth) <= 1e7, depth,
                     "with branching, at most 10^7 leaves");
  CANDI_CHECK_OPTION_GE(train_descriptors, 1000);
  CANDI_CHECK_OPTION_GE(kmeans_iterations, 1);
}

int64_t VocabularyTree::Leaves() const {
  int64_t n = 1;
  for (int l = 0; l < depth; ++l) n *= branching;
  return n;
}

int64_t VocabularyTree::Leaf(const uint8_t* descriptor) const {
  int64_t node = 0;
  for (int level = 0; level < depth; ++level) {
    const std::vector<float>& centres = nodes[node];
    const int child = centres.empty() ? 0 : Nearest(descriptor, centres, branching);
    node = node * branching + 1 + child;
  }
  // The first leaf's id: the internal nodes before it, (b^depth - 1) / (b - 1).
  int64_t first_leaf = 0, width = 1;
  for (int level = 0; level < depth; ++level) first_leaf += width, width *= branching;
  return node - first_leaf;
}

VocabularyTree TrainVocabularyTree(const std::vector<DatabaseImage>& images, const PairSelectionOptions& options) {
  options.Check();
  VocabularyTree tree;
  tree.branching = options.branching;
  tree.depth = options.depth;
  int64_t internal = 0, width = 1;
  for (int level = 0; level < tree.depth; ++level) internal += width, width *= tree.branching;
  tree.nodes.resize(internal);
  // The sample: evenly spaced over all descriptors, from a seeded offset.
  uint64_t total = 0;
  for (const DatabaseImage& image : images) total += image.rows;
  if (total == 0) return tree;
  const uint64_t count = std::min<uint64_t>(total, options.train_descriptors);
  Rng rng(options.seed ^ 0x70cab);
  const double offset = rng.Uniform();
  std::vector<float> data(count * kDims);
  {
    size_t image = 0;
    uint64_t before = 0;  // descriptors in images[0 .. image)
    for (uint64_t k = 0; k < count; ++k) {
      const uint64_t index = std::min<uint64_t>(total - 1, static_cast<uint64_t>((k + offset) * total / count));
      while (index >= before + images[image].rows) before += images[image].rows, ++image;
      const uint8_t* d = images[image].descriptors.data() + (index - before) * kDims;
      std::copy(d, d + kDims, data.begin() + k * kDims);
    }
  }
  // Level by level: each node's members split among its children.
  std::vector<std::vector<uint32_t>> members(1);
  members[0].resize(count);
  for (uint64_t i = 0; i < count; ++i) members[0][i] = static_cast<uint32_t>(i);
  int64_t level_first = 0;
  for (int level = 0; level < tree.depth; ++level) {
    const int64_t level_nodes = static_cast<int64_t>(members.size());
    std::vector<std::vector<uint32_t>> next(static_cast<size_t>(level_nodes) * tree.branching);
    for (int64_t j = 0; j < level_nodes; ++j) {
      if (members[j].empty()) continue;
      const int64_t node = level_first + j;
      std::vector<int> assignment;
      tree.nodes[node] = KMeans(data, members[j], tree.branching, options.kmeans_iterations,
                                options.seed * 0x9E3779B97F4A7C15ULL + static_cast<uint64_t>(node), &assignment);
      for (size_t i = 0; i < members[j].size(); ++i)
        next[static_cast<size_t>(j) * tree.branching + assignment[i]].push_back(members[j][i]);
      std::vector<uint32_t>().swap(members[j]);
    }
    level_first += level_nodes;
    members.swap(next);
  }
  return tree;
}

std::vector<std::vector<std::pair<size_t, double>>> RetrieveNeighbours(const VocabularyTree& tree,
                                                                       const std::vector<DatabaseImage>& images,
                                                                       int k) {
  const size_t n = images.size();
  // Each image's words (leaf, count), sorted by leaf.
  std::vector<std::vector<std::pair<int64_t, double>>> words(n);
  ParallelFor(size_t{0}, n, [&](size_t i) {
    std::vector<int64_t> leaves(images[i].rows);
    for (int64_t r = 0; r < images[i].rows; ++r) leaves[r] = tree.Leaf(images[i].descriptors.data() + r * kDims);
    std::sort(leaves.begin(), leaves.end());
    for (size_t r = 0; r < leaves.size(); ++r) {
      if (r == 0 || leaves[r] != leaves[r - 1]) words[i].push_back({leaves[r], 0.0});
      words[i].back().second += 1.0;
    }
  });
  // tf-idf, L2-normalised; the inverted file (leaf -> (image, weight)) in image order.
  std::vector<uint32_t> frequency(static_cast<size_t>(tree.Leaves()), 0);
  for (const auto& w : words)
    for (const auto& [leaf, count] : w) ++frequency[leaf];
  std::vector<std::vector<std::pair<uint32_t, float>>> postings(frequency.size());
  for (size_t i = 0; i < n; ++i) {
    double norm = 0;
    for (auto& [leaf, weight] : words[i]) {
      weight *= std::log(static_cast<double>(n) / frequency[leaf]);
      norm += weight * weight;
    }
    norm = std::sqrt(norm);
    for (auto& [leaf, weight] : words[i]) {
      weight = norm > 0 ? weight / norm : 0.0;
      if (weight > 0) postings[leaf].push_back({static_cast<uint32_t>(i), static_cast<float>(weight)});
    }
  }
  std::vector<std::vector<std::pair<size_t, double>>> result(n);
  ParallelFor(size_t{0}, n, [&](size_t i) {
    std::vector<double> score(n, 0.0);
    for (const auto& [leaf, weight] : words[i]) {
      if (weight == 0) continue;
      for (const auto& [j, w] : postings[leaf]) score[j] += weight * w;
    }
    score[i] = 0;
    std::vector<std::pair<size_t, double>> ranked;
    for (size_t j = 0; j < n; ++j)
      if (score[j] > 0) ranked.push_back({j, score[j]});
    const size_t keep = std::min<size_t>(ranked.size(), static_cast<size_t>(std::max(0, k)));
    std::partial_sort(ranked.begin(), ranked.begin() + keep, ranked.end(), [](const auto& a, const auto& b) {
      return a.second != b.second ? a.second > b.second : a.first < b.first;
    });
    ranked.resize(keep);
    result[i] = std::move(ranked);
  });
  return result;
}

PairSelection SelectPairs(const std::vector<DatabaseImage>& images,
                          const std::map<std::string, Eigen::Vector3d>& positions,
                          const PairSelectionOptions& options) {
  options.Check();
  PairSelection out;
  const size_t n = images.size();
  PairStrategy strategy = options.strategy;
  size_t with_position = 0;
  for (const DatabaseImage& image : images) with_position += positions.count(image.name);
  const bool many = strategy == PairStrategy::kAuto && n > static_cast<size_t>(options.exhaustive_max_images);
  const bool use_sequence = strategy == PairStrategy::kSequential || many;
  const bool use_retrieval = strategy == PairStrategy::kRetrieval || many;
  const bool use_positions = (strategy == PairStrategy::kPositional || many) && with_position > 0;
  if (strategy == PairStrategy::kExhaustive || (strategy == PairStrategy::kAuto && !many)) {
    for (size_t i = 0; i < n; ++i)
      for (size_t j = i + 1; j < n; ++j) out.pairs.push_back({i, j});
    out.strategy = "exhaustive";
    return out;
  }
  std::set<std::pair<size_t, size_t>> pairs;
  std::string text;
  if (use_sequence) {
    for (size_t i = 0; i < n; ++i)
      for (size_t j = i + 1; j < n && j <= i + static_cast<size_t>(options.sequential_overlap); ++j) {
        AddPair(i, j, &pairs);
        ++out.sequential;
      }
    text = "sequential " + std::to_string(options.sequential_overlap);
  }
  if (use_retrieval && options.retrieval_neighbours > 0) {
    // Each photo's most similar ones beyond those the sequence pairs it with already: on a walk
    // its sequence neighbours are also its most similar, and would use up the retrieval's share.
    const VocabularyTree tree = TrainVocabularyTree(images, options);
    const int sequence_pairs = use_sequence ? 2 * options.sequential_overlap : 0;
    const auto neighbours = RetrieveNeighbours(tree, images, options.retrieval_neighbours + sequence_pairs);
    for (size_t i = 0; i < n; ++i) {
      int added = 0;
      for (const auto& [j, score] : neighbours[i]) {
        if (added == options.retrieval_neighbours) break;
        if (use_sequence && (j > i ? j - i : i - j) <= static_cast<size_t>(options.sequential_overlap)) {
          continue;  // its sequence neighbour
        }
        AddPair(i, j, &pairs);
        ++out.retrieval;
        ++added;
      }
    }
    text += (text.empty() ? "" : " + ") + std::string("retrieval ") + std::to_string(options.retrieval_neighbours) +
            " (vocabulary tree " + std::to_string(options.branching) + "^" + std::to_string(options.depth) + ")";
  }
  if (use_positions && options.position_neighbours > 0) {
    std::vector<std::pair<size_t, Eigen::Vector3d>> placed;
    for (size_t i = 0; i < n; ++i) {
      const auto it = positions.find(images[i].name);
      if (it != positions.end()) placed.push_back({i, it->second});
    }
    for (const auto& [i, p] : placed) {
      std::vector<std::pair<double, size_t>> by_distance;
      for (const auto& [j, q] : placed)
        if (j != i) by_distance.push_back({(p - q).squaredNorm(), j});
      const size_t keep = std::min<size_t>(by_distance.size(), options.position_neighbours);
      std::partial_sort(by_distance.begin(), by_distance.begin() + keep, by_distance.end());
      for (size_t m = 0; m < keep; ++m) {
        AddPair(i, by_distance[m].second, &pairs);
        ++out.positional;
      }
    }
    text += (text.empty() ? "" : " + ") + std::string("positions ") + std::to_string(options.position_neighbours) +
            " (" + std::to_string(placed.size()) + " priors)";
  }
  out.pairs.assign(pairs.begin(), pairs.end());
  out.strategy = text.empty() ? "none" : text;
  return out;
}

std::vector<std::pair<size_t, size_t>> TransitivePairs(size_t n, const std::vector<std::pair<size_t, size_t>>& verified,
                                                       const std::set<std::pair<size_t, size_t>>& tried,
                                                       int neighbours) {
  CANDI_CHECK_LE(1, neighbours);
  std::vector<std::vector<size_t>> adjacent(n);
  for (const auto& [a, b] : verified) {
    CANDI_CHECK(a < n && b < n && a != b) << "verified pair (" << a << ", " << b << ") of " << n << " images";
    adjacent[a].push_back(b);
    adjacent[b].push_back(a);
  }
  for (auto& list : adjacent) {
    std::sort(list.begin(), list.end());
    list.erase(std::unique(list.begin(), list.end()), list.end());
  }
  // Image a's candidates: c two steps away, counted once a shared neighbour b.
  std::vector<std::vector<size_t>> proposed(n);
  ParallelFor(size_t{0}, n, [&](size_t a) {
    std::map<size_t, int> shared;
    for (size_t b : adjacent[a])
      for (size_t c : adjacent[b])
        if (c != a && !tried.count({std::min(a, c), std::max(a, c)})) ++shared[c];
    std::vector<std::pair<int, size_t>> ranked;  // (-shared, c): most shared first, ties by index
    ranked.reserve(shared.size());
    for (const auto& [c, count] : shared) ranked.push_back({-count, c});
    const size_t keep = std::min<size_t>(ranked.size(), static_cast<size_t>(neighbours));
    std::partial_sort(ranked.begin(), ranked.begin() + keep, ranked.end());
    for (size_t k = 0; k < keep; ++k) proposed[a].push_back(ranked[k].second);
  });
  std::set<std::pair<size_t, size_t>> pairs;
  for (size_t a = 0; a < n; ++a)
    for (size_t c : proposed[a]) AddPair(a, c, &pairs);
  return {pairs.begin(), pairs.end()};
}

std::map<std::string, Eigen::Vector3d> ReadPositionPriors(const std::string& path) {
  const io::CsvTable table = io::CsvTable::Read(path, {"name", "E", "N", "H"});
  std::map<std::string, Eigen::Vector3d> priors;
  for (const io::CsvTable::Row& row : table.rows()) {
    const Eigen::Vector3d p(table.Number(row, "E"), table.Number(row, "N"), table.Number(row, "H"));
    const std::string& name = table.Text(row, "name");
    if (name.empty()) table.Fail(row, "name", "empty");
    if (!priors.emplace(name, p).second) table.Fail(row, "name", "'" + name + "' given twice");
  }
  return priors;
}

}  // namespace candi::photogrammetry

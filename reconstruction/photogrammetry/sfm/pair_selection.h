// Which image pairs to match when every pair is too many: by image retrieval (candi's own
// vocabulary tree, trained on the campaign's own descriptors), by sequence (each photo with the
// next ones of its folder, in name order), and by position (each photo with its nearest by the
// GPS-like priors). The pairs grow as k N, not N^2; retrieval closes the loops that sequences
// leave open (a walk that returns to its start, the borders of separately taken sessions, the row
// above on the same wall). With the sequence, a photo's retrieval neighbours are counted beyond its
// sequence neighbours, which on a walk are also its most similar. After verification, rounds of
// transitive matching add the pairs whose photos share verified neighbours (a-b and b-c verified,
// a-c never tried), as COLMAP's transitive_matcher does: the weak pairs between rows and terraces
// that no photo's nearest neighbours reach, at most `transitive_neighbours` a photo a round.
//
// The vocabulary tree: hierarchical k-means (k-means++ seeding from a seeded generator, Lloyd
// iterations) of a sample of the descriptors, `branching` children a node, `depth` levels; each
// image becomes a tf-idf weighted, L2-normalised histogram of its descriptors' leaves, and its
// neighbours are the images whose histograms have the largest dot products (an inverted file).
// Every step is deterministic: the same descriptors and seed give the same pairs on any thread
// count (sums in a fixed order; ties broken by the lower index).
// Thread-safety: pure functions.
#pragma once

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "reconstruction/photogrammetry/sfm/colmap_database.h"

namespace candi::photogrammetry {

enum class PairStrategy { kAuto, kExhaustive, kSequential, kRetrieval, kPositional };
std::string PairStrategyName(PairStrategy strategy);  // "auto", "exhaustive", ...
// Parses a name of PairStrategyName; throws std::invalid_argument listing the names.
PairStrategy ParsePairStrategy(const std::string& name);

struct PairSelectionOptions {
  PairStrategy strategy = PairStrategy::kAuto;
  int exhaustive_max_images = 50;  // auto: every pair up to this many images, >= 2
  int sequential_overlap = 10;     // sequence: each photo with the next this many of its folder, >= 0
  int retrieval_neighbours = 20;   // retrieval: each photo with its this many most similar (beyond its
                                   // sequence neighbours, when the sequence is used too), >= 0
  int position_neighbours = 10;    // positions: each photo with its this many nearest, >= 0
  int transitive_rounds = 2;       // after verification, rounds of transitive matching (not after
                                   // exhaustive matching), >= 0
  int transitive_neighbours = 15;  // transitive: a photo's new pairs a round, most shared verified
                                   // neighbours first, >= 1
  int branching = 10;              // vocabulary tree children a node, [2, 64]
  int depth = 4;                   // vocabulary tree levels, [1, 8]
  int train_descriptors = 200000;  // descriptors sampled to train the tree, >= 1000
  int kmeans_iterations = 8;       // Lloyd iterations a node, >= 1
  uint64_t seed = 0;               // the training sample and the k-means seeding
  void Check() const;
};

// A vocabulary tree: `centres` of every node's children, level by level.
struct VocabularyTree {
  int branching = 0, depth = 0;
  // nodes[n] holds node n's children's centres (branching x 128, row-major), empty for a node with
  // no descriptors; the children of node n are nodes n * branching + 1 ... (a complete tree).
  std::vector<std::vector<float>> nodes;
  int64_t Leaves() const;  // branching^depth
  // The leaf a descriptor (128 bytes) falls in, [0, Leaves()).
  int64_t Leaf(const uint8_t* descriptor) const;
};
// Trains the tree on a seeded sample of the images' descriptors (all of them when fewer).
VocabularyTree TrainVocabularyTree(const std::vector<DatabaseImage>& images, const PairSelectionOptions& options);

// For each image, its `k` most similar others by tf-idf of `tree`'s leaves: (index, score) by
// decreasing score, ties by index. Images with no features get no neighbours.
std::vector<std::vector<std::pair<size_t, double>>> RetrieveNeighbours(const VocabularyTree& tree,
                                                                       const std::vector<DatabaseImage>& images,
                                                                       int k);

struct PairSelection {
  std::vector<std::pair<size_t, size_t>> pairs;  // i < j, sorted, unique
  std::string strategy;                          // what was done: "exhaustive", "sequential 10 + retrieval 20", ...
  size_t sequential = 0, retrieval = 0, positional = 0;  // pairs each source proposed (they overlap)
};

// The pairs to match among `images` (sorted by name, so a session's folder or prefix keeps its
// photos together and in order). `positions` maps an image name to its prior position (any
// metric frame); images without one are matched only by the other sources. Auto: exhaustive up to
// exhaustive_max_images; above, sequential + retrieval, and positional where priors exist.
PairSelection SelectPairs(const std::vector<DatabaseImage>& images,
                          const std::map<std::string, Eigen::Vector3d>& positions,
                          const PairSelectionOptions& options);

// The pairs a round of transitive matching adds among `n` images: (a, c) never `tried` where a-b
// and b-c are `verified` for some b. Each image proposes its `neighbours` candidates with the most
// such b (ties by the lower index); a pair is added when either of its images proposes it. i < j,
// sorted, unique; at most n * neighbours.
std::vector<std::pair<size_t, size_t>> TransitivePairs(size_t n, const std::vector<std::pair<size_t, size_t>>& verified,
                                                       const std::set<std::pair<size_t, size_t>>& tried,
                                                       int neighbours);

// Reads priors.csv (name,E,N,H[,sigma], header required, '#' comments): image name -> position.
// InputError naming the file, line and field for a bad row or a name given twice.
std::map<std::string, Eigen::Vector3d> ReadPositionPriors(const std::string& path);

}  // namespace candi::photogrammetry

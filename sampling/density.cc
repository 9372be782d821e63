#include "sampling/density.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <nanoflann.hpp>
#include <stdexcept>

#include "core/check.h"
#include "core/kd_tree_adaptor.h"
#include "core/log.h"
#include "core/parallel.h"
#include "core/rng.h"
#include "core/text_format.h"
#include "sampling/plane_in_cube.h"

namespace candi::sampling {

namespace {

constexpr uint64_t kSampleStream = 0x64656e73697479ULL;  // "density": the radius sample
constexpr size_t kBlock = 4096;                          // points per task and progress step
constexpr double kPi = 3.14159265358979323846;
constexpr int kKeyBits = 21;  // voxel key bits per axis

// Positions as float offsets from the bounding-box centre: float keeps ~7 digits, spent on the
// cloud's extent instead of on its distance from the origin (survey coordinates).
using FloatCloud = KdTreeAdaptor<Eigen::Vector3f>;
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, FloatCloud>,
                                                   FloatCloud, 3, uint32_t>;

// A nanoflann result set that sums the weights of the points within the radius instead of
// storing them (no allocation per query; coincident points cost no memory).
class WeightSum {
 public:
  WeightSum(float radius_sq, const std::vector<double>& weights)
      : radius_sq_(radius_sq), weights_(weights) {}
  bool addPoint(float dist_sq, uint32_t index) {
    if (dist_sq < radius_sq_) {
      sum_ += weights_.empty() ? 1.0 : weights_[index];
      ++count_;
    }
    return true;
  }
  float worstDist() const { return radius_sq_; }
  bool full() const { return true; }
  size_t size() const { return count_; }
  double sum() const { return sum_; }

 private:
  float radius_sq_;
  const std::vector<double>& weights_;
  double sum_ = 0.0;
  size_t count_ = 0;
};

Box3d CheckedBounds(const PointCloud& cloud) {
  for (size_t i = 0; i < cloud.size(); ++i) {
    CANDI_CHECK(cloud.positions[i].allFinite())
        << "EstimateSurfaceDensity: point " << i << " has a non-finite position ("
        << cloud.positions[i].transpose() << "); readers never produce one, so filter it first";
  }
  return cloud.LocalBounds();
}

// The weight of each point, or an empty vector for "all 1".
std::vector<double> ReadWeights(const PointCloud& cloud, const std::string& field_name) {
  if (field_name.empty()) return {};
  const ScalarField* field = cloud.FindScalar(field_name);
  if (field == nullptr) {
    throw std::invalid_argument("DensityOptions::weight_field = '" + field_name +
                                "'; must name a scalar field of the cloud");
  }
  std::vector<double> weights(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    weights[i] = field->Get(i);
    if (!std::isfinite(weights[i]) || weights[i] < 0) {
      throw InputError("scalar field '" + field_name + "' of point " + std::to_string(i) + " = " +
                       FormatSignificant(weights[i], 10) + "; a weight must be finite and >= 0");
    }
  }
  return weights;
}

FloatCloud ToFloatCloud(const PointCloud& cloud, const Eigen::Vector3d& centre) {
  FloatCloud out;
  out.points.resize(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3d p = cloud.positions[i] - centre;
    for (int k = 0; k < 3; ++k) out.points[i][k] = static_cast<float>(p[k]);
  }
  return out;
}

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  auto mid = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

// Median over a seeded sample of the distance to the k-th nearest other point.
double MedianKthDistance(const KdTree& tree, const FloatCloud& points, const DensityOptions& o) {
  const size_t n = points.kdtree_get_point_count();
  const size_t samples = std::min(n, static_cast<size_t>(o.sample_size));
  const size_t k = std::min(n, static_cast<size_t>(o.target_neighbours) + 1);  // + the point
  std::vector<double> distances(samples);
  std::vector<uint32_t> found(k);
  std::vector<float> dist_sq(k);
  for (size_t j = 0; j < samples; ++j) {
    const size_t i = samples == n ? j : HashIndex(o.seed, j, kSampleStream) % n;
    const size_t got = tree.knnSearch(points.points[i].data(), k, found.data(), dist_sq.data());
    distances[j] = got > 0 ? std::sqrt(static_cast<double>(dist_sq[got - 1])) : 0.0;
  }
  return Median(std::move(distances));
}

// The rule for degenerate clouds (file comment of density.h).
double FallbackRadius(const Box3d& box, size_t n, int k) {
  Eigen::Vector3d e = box.Extent();
  std::sort(e.data(), e.data() + 3, [](double a, double b) { return a > b; });
  const double r = std::sqrt(k * e[0] * e[1] / (kPi * static_cast<double>(n)));
  if (r > 0) return r;
  return e[0] > 0 ? 0.5 * e[0] : 1.0;
}

double AutomaticRadius(const DensityOptions& o, const KdTree& tree, const FloatCloud& points,
                       const Box3d& box) {
  const double r = MedianKthDistance(tree, points, o);
  if (r > 0) return r;
  LogWarning("density: over half the sampled points have " + std::to_string(o.target_neighbours) +
             " coincident copies; radius from the bounding box instead");
  return FallbackRadius(box, points.kdtree_get_point_count(), o.target_neighbours);
}

// Counting every point against its own radius search, in the tree's (spatially coherent) order.
void KdTreeDensity(const DensityOptions& o, const KdTree& tree, const FloatCloud& points,
                   const std::vector<double>& weights, DensityResult* result) {
  const float radius_sq = static_cast<float>(result->radius * result->radius);
  const double inverse_area = 1.0 / result->area;
  const size_t n = points.kdtree_get_point_count();
  ForEachBlock(o.threads, n, kBlock, o.progress, [&](size_t begin, size_t end) {
    for (size_t k = begin; k < end; ++k) {
      const uint32_t i = tree.vAcc[k];
      WeightSum sum(radius_sq, weights);
      tree.findNeighbors(sum, points.points[i].data(), nanoflann::SearchParams());
      const double self = weights.empty() ? 1.0 : std::min(weights[i], 1.0);
      result->density[i] = std::max(sum.sum() - self, 0.0) * inverse_area;
    }
  });
}

struct CellEntry {
  uint64_t key;
  uint32_t index;
  bool operator<(const CellEntry& o) const { return key != o.key ? key < o.key : index < o.index; }
};

// Cell keys (21 bits per axis), sorted by key then index: a deterministic grouping.
std::vector<CellEntry> SortedCells(const DensityOptions& o, const PointCloud& cloud,
                                   const Box3d& box, double h) {
  const Eigen::Vector3d cells = (box.Extent() / h).array().floor() + 1.0;
  if (cells.maxCoeff() > double{1 << kKeyBits}) {
    throw std::invalid_argument(
        "DensityOptions::radius = " + FormatSignificant(h / std::sqrt(kPi), 10) +
        " makes a voxel grid of " + FormatSignificant(cells.maxCoeff(), 10) +
        " cells along an axis; must be <= 2^21 (use a larger radius or "
        "the kd-tree method)");
  }
  std::vector<CellEntry> entries(cloud.size());
  ForEachBlock(o.threads, cloud.size(), kBlock, nullptr, [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      uint64_t key = 0;
      for (int k = 0; k < 3; ++k) {
        const double c = std::floor((cloud.positions[i][k] - box.min[k]) / h);
        key = (key << kKeyBits) | static_cast<uint64_t>(std::clamp(c, 0.0, cells[k] - 1));
      }
      entries[i] = {key, static_cast<uint32_t>(i)};
    }
  });
  auto sort = [&] { tbb::parallel_sort(entries.begin(), entries.end()); };
  if (o.threads > 0) {
    tbb::task_arena(o.threads).execute(sort);
  } else {
    sort();
  }
  return entries;
}

// The area of the cell's section by the plane fitted to its points (PCA through their mean), in
// m^2; h^2 when they define no plane (fewer than 3 points, collinear or coincident).
double CellSectionArea(const PointCloud& cloud, const Eigen::Vector3d& corner, double h,
                       const CellEntry* first, size_t count) {
  if (count < 3) return h * h;
  // Two passes (mean, then scatter about it): no cancellation in the covariance.
  auto unit = [&](size_t k) { return ((cloud.positions[first[k].index] - corner) / h).eval(); };
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (size_t k = 0; k < count; ++k) mean += unit(k);
  mean /= static_cast<double>(count);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (size_t k = 0; k < count; ++k) {
    const Eigen::Vector3d d = unit(k) - mean;
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(cov);
  const Eigen::Vector3d& lambda = solver.eigenvalues();  // ascending
  if (!(lambda[1] > 1e-12 * lambda[2])) return h * h;    // collinear or coincident: no plane
  const Eigen::Vector3d normal = solver.eigenvectors().col(0);
  const double area = PlaneInCubeArea(normal, normal.dot(mean));
  return area > 0 ? area * h * h : h * h;
}

// The corner (minimum) of the cell with this key.
Eigen::Vector3d CellCorner(uint64_t key, const Box3d& box, double h) {
  constexpr uint64_t kMask = (uint64_t{1} << kKeyBits) - 1;
  const Eigen::Vector3d index(static_cast<double>(key >> (2 * kKeyBits)),
                              static_cast<double>((key >> kKeyBits) & kMask),
                              static_cast<double>(key & kMask));
  return box.min + index * h;
}

void VoxelDensity(const DensityOptions& o, const PointCloud& cloud, const Box3d& box,
                  const std::vector<double>& weights, DensityResult* result) {
  const double h = result->cell_size;
  const std::vector<CellEntry> entries = SortedCells(o, cloud, box, h);
  std::vector<size_t> starts;  // first entry of each cell, then the end
  for (size_t k = 0; k < entries.size(); ++k) {
    if (k == 0 || entries[k].key != entries[k - 1].key) starts.push_back(k);
  }
  starts.push_back(entries.size());
  const size_t cells = starts.size() - 1;
  std::atomic<uint64_t> done{0};
  ForEachBlock(o.threads, cells, kBlock, nullptr, [&](size_t begin, size_t end) {
    for (size_t c = begin; c < end; ++c) {
      const CellEntry* first = &entries[starts[c]];
      const size_t count = starts[c + 1] - starts[c];
      double total = static_cast<double>(count);
      if (!weights.empty()) {
        total = 0.0;
        for (size_t k = 0; k < count; ++k) total += weights[first[k].index];
      }
      const Eigen::Vector3d corner = CellCorner(first->key, box, h);
      const double area = CellSectionArea(cloud, corner, h, first, count);
      for (size_t k = 0; k < count; ++k) {
        const uint32_t i = first[k].index;
        const double self = weights.empty() ? 1.0 : std::min(weights[i], 1.0);
        result->density[i] = std::max(total - self, 0.0) / area;
      }
    }
    if (o.progress) o.progress(done += starts[end] - starts[begin], entries.size());
  });
}

}  // namespace

std::string DensityMethodName(DensityMethod method) {
  return method == DensityMethod::kVoxel ? "voxel" : "kdtree";
}

DensityMethod ParseDensityMethod(const std::string& name) {
  if (name == "kdtree") return DensityMethod::kKdTree;
  if (name == "voxel") return DensityMethod::kVoxel;
  throw std::invalid_argument("density method '" + name + "'; must be kdtree or voxel");
}

void DensityOptions::Check() const {
  CANDI_CHECK_OPTION(radius >= 0 && std::isfinite(radius), radius,
                     "finite and >= 0 (0 = automatic)");
  CANDI_CHECK_OPTION_GE(target_neighbours, 1);
  CANDI_CHECK_OPTION_GE(sample_size, 1);
  CANDI_CHECK_OPTION(threads >= 0, threads, ">= 0 (0 = all available)");
}

DensityResult EstimateSurfaceDensity(const DensityOptions& options, const PointCloud& cloud) {
  options.Check();
  DensityResult result;
  result.method = options.method;
  if (cloud.empty()) return result;
  CANDI_CHECK(cloud.size() < (uint64_t{1} << 32)) << "EstimateSurfaceDensity: over 2^32 points";
  const Box3d box = CheckedBounds(cloud);
  const std::vector<double> weights = ReadWeights(cloud, options.weight_field);
  // The tree serves the kd-tree counts and the automatic radius; a voxel run with a given radius
  // needs none.
  FloatCloud points;
  std::unique_ptr<KdTree> tree;
  if (options.method == DensityMethod::kKdTree || !(options.radius > 0)) {
    points = ToFloatCloud(cloud, box.Center());
    tree = std::make_unique<KdTree>(3, points, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  }
  result.automatic_radius = !(options.radius > 0);
  result.radius =
      result.automatic_radius ? AutomaticRadius(options, *tree, points, box) : options.radius;
  result.area = kPi * result.radius * result.radius;
  if (tree && result.radius < 1e-5 * box.Extent().maxCoeff()) {  // float offsets in the tree
    LogWarning("density: radius " + FormatSignificant(result.radius, 10) +
               " m is below float resolution for an extent of " +
               FormatSignificant(box.Extent().maxCoeff(), 10) + " m; densities are approximate");
  }
  result.density.assign(cloud.size(), 0.0);
  if (options.method == DensityMethod::kKdTree) {
    KdTreeDensity(options, *tree, points, weights, &result);
  } else {
    result.cell_size = std::sqrt(kPi) * result.radius;
    VoxelDensity(options, cloud, box, weights, &result);
  }
  result.median_density = Median(result.density);
  LogDebug("density: " + DensityMethodName(options.method) + ", radius " +
           FormatSignificant(result.radius, 10) + " m, median " +
           FormatSignificant(result.median_density, 10) + " points/m^2");
  return result;
}

}  // namespace candi::sampling

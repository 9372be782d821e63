// The spatial index of the deviation methods (nanoflann kd-trees, double): included by
// compare/*.cc only, so nanoflann stays out of public headers.
//
// nanoflann 1.4 (Debian 12) builds a tree on one thread, which at 10^7 points took most of a
// comparison's time. PointTree cuts points that are in Morton order (MortonOrder) into parts of
// consecutive points, compact in space, and builds one tree a part in parallel; a query visits
// the parts whose bounding box lies within its current bound. The number of parts depends on the
// point count only, so results do not depend on the threads. Distances are exact; where two
// points are equally near, which one a query names may differ from a single tree's choice (the
// distance does not).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <nanoflann.hpp>
#include <vector>

#include "compare/deviation.h"
#include "core/box.h"
#include "core/parallel.h"

namespace candi::compare::internal {

// Points seen by nanoflann without a copy.
struct PointSpan {
  const Eigen::Vector3d* data = nullptr;
  size_t n = 0;
  size_t kdtree_get_point_count() const { return n; }
  double kdtree_get_pt(uint32_t i, size_t dim) const { return data[i][static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using SpanTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, PointSpan>,
                                                     PointSpan, 3, uint32_t>;

class PointTree {
 public:
  static constexpr size_t kPartPoints = size_t{1} << 21;  // points a part, about
  static constexpr size_t kMaxParts = 64;

  // `points`' elements (finite, best in Morton order) must outlive the tree, unchanged; the
  // vector itself may be moved (the tree keeps its buffer, not the vector). `part_points`
  // (tests) sets the parts' size.
  explicit PointTree(const std::vector<Eigen::Vector3d>& points, size_t part_points = kPartPoints)
      : points_(points.data()), size_(points.size()) {
    const size_t n = points.size();
    const size_t parts = std::clamp<size_t>((n + part_points - 1) / part_points, 1, kMaxParts);
    for (size_t k = 0; k <= parts; ++k) begin_.push_back(n * k / parts);
    spans_.resize(parts);
    boxes_.resize(parts);
    trees_.resize(parts);
    ParallelFor(size_t{0}, parts, [&](size_t k) {
      spans_[k] = {points.data() + begin_[k], begin_[k + 1] - begin_[k]};
      for (size_t i = begin_[k]; i < begin_[k + 1]; ++i) boxes_[k].Extend(points[i]);
      trees_[k] = std::make_unique<SpanTree>(3, spans_[k], nanoflann::KDTreeSingleIndexAdaptorParams(10));
      trees_[k]->buildIndex();
    });
  }

  size_t size() const { return size_; }
  const Eigen::Vector3d& point(size_t i) const { return points_[i]; }

  // The point nearest q; the search starts bounded by point `hint` (an index, or -1). Returns
  // its index (-1 only for an empty tree).
  int64_t Nearest(const Eigen::Vector3d& q, int64_t hint) const {
    Best best;
    if (hint >= 0) {
      best.index = hint;
      best.dist_sq = (q - points_[static_cast<size_t>(hint)]).squaredNorm();
    }
    const size_t first = hint >= 0 ? PartOf(static_cast<size_t>(hint)) : 0;
    for (size_t j = 0; j < trees_.size(); ++j) {
      const size_t k = (first + j) % trees_.size();
      if (!(BoxDistSq(k, q) < best.dist_sq) && best.index >= 0) continue;
      NearestSet set(&best, begin_[k]);
      trees_[k]->findNeighbors(set, q.data(), nanoflann::SearchParams());
    }
    return best.index;
  }

  // The k nearest points, nearest first: their indices and squared distances. Returns how many
  // (k, or fewer when the tree holds fewer).
  size_t Knn(const Eigen::Vector3d& q, size_t k, uint32_t* index, double* dist_sq) const {
    KnnSet set(k, index, dist_sq);
    // The parts nearest first, so that the first one searched bounds the others.
    std::pair<double, size_t> order[kMaxParts];
    const size_t parts = trees_.size();
    for (size_t part = 0; part < parts; ++part) order[part] = {BoxDistSq(part, q), part};
    std::sort(order, order + parts);
    for (size_t j = 0; j < parts; ++j) {
      const auto [box_sq, part] = order[j];
      if (set.count() == k && !(box_sq < set.worstDist())) break;
      set.offset = static_cast<uint32_t>(begin_[part]);
      trees_[part]->findNeighbors(set, q.data(), nanoflann::SearchParams());
    }
    return set.count();
  }

  // Calls visit(index, dist_sq) for every point within `radius` of q.
  template <typename Visit>
  void ForEachWithin(const Eigen::Vector3d& q, double radius, Visit visit) const {
    const double radius_sq = radius * radius;
    for (size_t part = 0; part < trees_.size(); ++part) {
      if (BoxDistSq(part, q) > radius_sq) continue;
      WithinSet<Visit> set(radius_sq, static_cast<uint32_t>(begin_[part]), visit);
      trees_[part]->findNeighbors(set, q.data(), nanoflann::SearchParams());
    }
  }

 private:
  struct Best {
    int64_t index = -1;
    double dist_sq = std::numeric_limits<double>::infinity();
  };
  // nanoflann result set: the nearest point across parts (ties keep the earlier one).
  class NearestSet {
   public:
    NearestSet(Best* best, size_t offset) : best_(best), offset_(offset) {}
    bool addPoint(double d, uint32_t i) {
      if (d < best_->dist_sq) {
        best_->dist_sq = d;
        best_->index = static_cast<int64_t>(offset_ + i);
      }
      return true;
    }
    double worstDist() const { return best_->dist_sq; }
    bool full() const { return best_->index >= 0; }

   private:
    Best* best_;
    size_t offset_;
  };
  // nanoflann result set: the k nearest across parts, kept sorted (insertion: k is small).
  class KnnSet {
   public:
    KnnSet(size_t k, uint32_t* index, double* dist_sq) : k_(k), index_(index), dist_sq_(dist_sq) {}
    bool addPoint(double d, uint32_t i) {
      if (count_ == k_ && !(d < dist_sq_[k_ - 1])) return true;
      size_t j = count_ < k_ ? count_++ : k_ - 1;
      while (j > 0 && dist_sq_[j - 1] > d) {
        dist_sq_[j] = dist_sq_[j - 1];
        index_[j] = index_[j - 1];
        --j;
      }
      dist_sq_[j] = d;
      index_[j] = offset + i;
      return true;
    }
    double worstDist() const {
      return count_ < k_ ? std::numeric_limits<double>::infinity() : dist_sq_[k_ - 1];
    }
    bool full() const { return count_ == k_; }
    size_t count() const { return count_; }
    uint32_t offset = 0;

   private:
    size_t k_, count_ = 0;
    uint32_t* index_;
    double* dist_sq_;
  };
  // nanoflann result set: hands every point within the radius to visit(index, dist_sq).
  template <typename Visit>
  class WithinSet {
   public:
    WithinSet(double radius_sq, uint32_t offset, Visit& visit)
        : radius_sq_(radius_sq), offset_(offset), visit_(visit) {}
    bool addPoint(double d, uint32_t i) {
      if (d <= radius_sq_) visit_(offset_ + i, d);
      return true;
    }
    double worstDist() const { return radius_sq_; }
    bool full() const { return true; }

   private:
    double radius_sq_;
    uint32_t offset_;
    Visit& visit_;
  };

  size_t PartOf(size_t i) const {
    return static_cast<size_t>(std::upper_bound(begin_.begin(), begin_.end(), i) - begin_.begin()) - 1;
  }
  double BoxDistSq(size_t part, const Eigen::Vector3d& q) const {
    const Box3d& b = boxes_[part];
    double sq = 0;
    for (int k = 0; k < 3; ++k) {
      const double g = std::max({0.0, b.min[k] - q[k], q[k] - b.max[k]});
      sq += g * g;
    }
    return sq;
  }

  const Eigen::Vector3d* points_;
  size_t size_;
  std::vector<size_t> begin_;  // parts: [begin_[k], begin_[k + 1])
  std::vector<PointSpan> spans_;
  std::vector<Box3d> boxes_;
  std::vector<std::unique_ptr<SpanTree>> trees_;
};

// M3C2 (m3c2.cc) of `compared` (NaN where not finite) against `reference` (finite, with its
// tree), the scales resolved (D and d > 0).
DeviationResult M3c2(const DeviationOptions& options, const std::vector<Eigen::Vector3d>& reference,
                     const PointTree& reference_tree, const std::vector<Eigen::Vector3d>& compared,
                     const ProgressCallback& progress);

}  // namespace candi::compare::internal

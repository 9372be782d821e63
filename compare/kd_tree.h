// The kd-tree of the deviation methods (nanoflann, double): included by compare/*.cc only, so
// nanoflann stays out of public headers.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <nanoflann.hpp>
#include <vector>

#include "compare/deviation.h"
#include "core/kd_tree_adaptor.h"

namespace candi::compare::internal {

using Points = KdTreeAdaptor<Eigen::Vector3d>;
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Points>,
                                                   Points, 3, uint32_t>;

// A tree over `points` (which must outlive it and stay unchanged); leaf size 10.
inline std::unique_ptr<KdTree> BuildTree(const Points& points) {
  auto tree = std::make_unique<KdTree>(3, points, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  tree->buildIndex();
  return tree;
}

// A nanoflann result set that hands every point within the radius to `visit(index, dist_sq)`
// instead of storing it (no allocation per query).
template <typename Visit>
class VisitWithin {
 public:
  VisitWithin(double radius_sq, Visit& visit) : radius_sq_(radius_sq), visit_(visit) {}
  bool addPoint(double dist_sq, uint32_t index) {
    if (dist_sq <= radius_sq_) visit_(index, dist_sq);
    return true;
  }
  double worstDist() const { return radius_sq_; }
  bool full() const { return true; }

 private:
  double radius_sq_;
  Visit& visit_;
};

// Calls visit(index, dist_sq) for every point of `tree` within `radius` of `query`.
template <typename Visit>
void ForEachWithin(const KdTree& tree, const Eigen::Vector3d& query, double radius, Visit visit) {
  VisitWithin<Visit> set(radius * radius, visit);
  tree.findNeighbors(set, query.data(), nanoflann::SearchParams());
}

// M3C2 (m3c2.cc) of `compared` (NaN where not finite) against `reference` (finite, with its
// tree), the scales resolved (D and d > 0).
DeviationResult M3c2(const DeviationOptions& options, const std::vector<Eigen::Vector3d>& reference,
                     const KdTree& reference_tree, const std::vector<Eigen::Vector3d>& compared,
                     const ProgressCallback& progress);

}  // namespace candi::compare::internal

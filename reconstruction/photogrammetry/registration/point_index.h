// PointIndex, a kd-tree of float points (pcl::KdTreeFLANN, exact search) for nearest-neighbour
// queries: the overlap and RMS figures of registration. Positions are in a common local frame
// (local_points.h).
// Not thread-safe for concurrent queries (FLANN's search keeps state); build once, query many.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

namespace candi::photogrammetry {

class PointIndex {
 public:
  // `points` must be finite (CANDI_CHECK); an empty index answers "none" to every query.
  explicit PointIndex(const std::vector<Eigen::Vector3f>& points);
  ~PointIndex();
  PointIndex(const PointIndex&) = delete;
  PointIndex& operator=(const PointIndex&) = delete;

  size_t size() const { return size_; }
  // For each query, the squared distance (m^2) to its nearest indexed point, or +infinity when
  // the index is empty. Each query is first transformed by `transform` (a rigid 4x4 in the same
  // local frame, applied in double).
  std::vector<double> NearestSquaredDistances(const std::vector<Eigen::Vector3f>& queries,
                                              const Eigen::Matrix4d& transform) const;
  // The index of the indexed point nearest to `query` and its squared distance (m^2, in double);
  // {-1, +infinity} when the index is empty.
  std::pair<int64_t, double> Nearest(const Eigen::Vector3d& query) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  size_t size_ = 0;
};

// Correspondence statistics of `queries` (moved by `transform`) against `index`: those whose
// nearest neighbour lies within `max_distance` count as overlapping.
struct OverlapStats {
  size_t queries = 0;
  size_t correspondences = 0;  // queries with a neighbour within max_distance
  double overlap = 0;          // correspondences / queries, [0, 1]; 0 without queries
  double rms = 0;              // RMS of those neighbour distances, m; NaN without correspondences
};
OverlapStats MeasureOverlap(const PointIndex& index, const std::vector<Eigen::Vector3f>& queries,
                            const Eigen::Matrix4d& transform, double max_distance);

}  // namespace candi::photogrammetry

// KdTreeAdaptor, not an index itself: points as nanoflann's kd-tree reads them (its dataset
// adaptor), for the .cc files that build a nanoflann::KDTreeSingleIndexAdaptor. This header does
// not include nanoflann: the tree, and so the heavy header, stays in those files.
//
// Point: a fixed-size Eigen vector (Eigen::Vector3f, Eigen::Vector2d, ...), the tree's scalar
// Point::Scalar and dimension Point::RowsAtCompileTime; indices uint32_t (under 2^32 points).
// No bounding box is given: nanoflann computes it from the points. The tree holds a reference to
// the adaptor, which must outlive it, with its points unchanged. For example:
//
//   using Cloud = KdTreeAdaptor<Eigen::Vector2d>;
//   using Tree = nanoflann::KDTreeSingleIndexAdaptor<
//       nanoflann::L2_Simple_Adaptor<double, Cloud>, Cloud, 2, uint32_t>;
//   Tree tree(2, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
//   tree.knnSearch(query.data(), k, indices, squared_distances);
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace candi {

template <typename Point>
struct KdTreeAdaptor {
  std::vector<Point> points;

  size_t kdtree_get_point_count() const { return points.size(); }
  typename Point::Scalar kdtree_get_pt(uint32_t i, size_t dim) const {
    return points[i][static_cast<int>(dim)];
  }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

}  // namespace candi

// Surface normals of float points by PCA over each point's k nearest neighbours
// (pcl::NormalEstimation, single-threaded so results do not depend on the thread count).
// Positions in a common local frame (local_points.h). A normal's sign is arbitrary (oriented
// towards +z where it is not horizontal); where the neighbourhood defines no plane (fewer than 3
// points, all coincident) the normal is NaN.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace candi::photogrammetry {

// neighbours >= 3 (CANDI_CHECK); points must be finite. One normal per point.
std::vector<Eigen::Vector3f> EstimateNormals(const std::vector<Eigen::Vector3f>& points,
                                             int neighbours);

}  // namespace candi::photogrammetry

// Float copies of point positions for PCL, which stores x/y/z as float.
//
// Survey coordinates (E ~ 4e5, N ~ 9e6 m) keep only ~0.5-1 m in float, so every cloud handed to
// PCL is first re-expressed relative to one double-precision origin (core/local_frame.h) shared
// by all clouds of the computation: p_float = float((p_local + frame.origin) - origin), exact up
// to the final rounding when the origins are integers. Near the origin float keeps ~1e-7 of the
// extent (10 um over 100 m).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/point_cloud.h"

namespace candi::photogrammetry {

// The common origin for clouds around `world_box`: its centre rounded to whole metres (integers
// keep the shift exact); zero for an empty box.
Eigen::Vector3d CommonOrigin(const Box3d& world_box);

// Positions of `cloud` (all points, or those in `indices`) relative to the world point `origin`,
// as float. Throws InputError("<name>: point i: position is not finite") on NaN or infinity.
std::vector<Eigen::Vector3f> LocalFloatPoints(const PointCloud& cloud,
                                              const Eigen::Vector3d& origin,
                                              const std::string& name);
std::vector<Eigen::Vector3f> LocalFloatPoints(const PointCloud& cloud,
                                              const std::vector<size_t>& indices,
                                              const Eigen::Vector3d& origin,
                                              const std::string& name);

// Throws InputError naming `name` and the first point whose position is not finite.
void CheckFinitePositions(const PointCloud& cloud, const std::string& name);

}  // namespace candi::photogrammetry

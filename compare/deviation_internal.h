// What the deviation methods share (deviation.cc, c2m.cc): positions about one common origin,
// input checks, and the parallel loop over compared points.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "compare/deviation.h"

namespace candi::compare::internal {

// The common origin for clouds around `world_box`: its centre rounded to whole metres (an integer
// shift is exact); zero for an empty box.
Eigen::Vector3d CommonOrigin(const Box3d& world_box);

// Positions of `cloud` relative to the world point `origin`: (p + (frame.origin - origin)), exact
// for integer origins. Positions that are not finite stay NaN (the callers decide).
std::vector<Eigen::Vector3d> RelativePositions(const PointCloud& cloud,
                                               const Eigen::Vector3d& origin);

// Throws InputError("<name>: holds no points") for an empty cloud.
void CheckNotEmpty(size_t size, const std::string& name, const char* what = "points");
// Throws InputError naming `name` for 2^32 points or more (the indices are 32-bit).
void CheckBelowIndexLimit(size_t size, const std::string& name);

// Compared points a task takes (core/parallel.h: ForEachBlock).
constexpr size_t kBlock = 2048;

// Counts NaN distances into result.undefined and states how many compared points were not finite
// (`not_finite`) and, when the compared cloud's box does not meet the reference's, that they lie
// apart (`gap` > 0, m).
void Finish(DeviationResult& result, uint64_t not_finite, double gap,
            const std::string& compared_name);

// The indices of `points` along a Z-order (Morton) curve over their bounding box, points that are
// not finite last: neighbours in space become neighbours in memory, so queries made in this order
// (and a tree built over points in it) stay in the cache. Deterministic (unique keys).
std::vector<uint32_t> MortonOrder(const std::vector<Eigen::Vector3d>& points);
// The 63-bit Morton codes MortonOrder sorts by (21 bits an axis over the finite points' bounding
// box; ~0 for a point that is not finite).
std::vector<uint64_t> MortonCodes(const std::vector<Eigen::Vector3d>& points);

// The world bounds of a cloud's finite positions (a NaN x beside a finite y counts for nothing).
Box3d FiniteWorldBounds(const PointCloud& cloud);

// The gap between two boxes, m (0 when they meet).
double BoxGap(const Box3d& a, const Box3d& b);

}  // namespace candi::compare::internal

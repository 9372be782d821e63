// Where a section cuts: a plane (a point and a normal), a vertical plane through two survey points,
// or a plan polyline whose vertical faces are unrolled into one drawing (a section along a wall).
//
// Drawing coordinates (x, y), metres, are what a surveyor's section sheet shows:
// - a vertical plane: x = chainage along the plane's horizontal axis u = n x z (from the given
//   point, or from the first of two points towards the second), y = elevation (world z);
// - a horizontal plane (a plan cut): x, y = world x, y (survey easting, northing);
// - a tilted plane: x along u = n x z, y along v = u x n (up the plane), plus the point's z;
// - a path: x = chainage along the polyline (0 at its first vertex), y = elevation. A point
//   belongs to the segment nearest to it in plan (ties to the earlier one); the segment's slab
//   also ends half a thickness beyond each end, so a corner's points are not lost.
// depth = signed distance from the plane (the segment's plane for a path), along its normal.
// All in world (survey) coordinates, double: 1e6-1e7 m keeps its millimetres (the arithmetic
// runs on differences from the section's own point).
// Failures: std::invalid_argument naming the option (a thickness <= 0 or not finite, a zero or
// non-finite normal, two coincident points, a path with fewer than two distinct vertices).
// Thread-safe (values).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "core/clip.h"

namespace candi::section {

class SectionPath {
 public:
  static SectionPath Plane(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double thickness);
  static SectionPath Through(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double thickness);
  // Consecutive repeated vertices (closer than 1e-9 m in plan) are merged; `merged` counts them.
  static SectionPath Path(const std::vector<Eigen::Vector2d>& plan, double thickness, size_t* merged = nullptr);

  bool is_path() const { return !path_.empty(); }
  double thickness() const { return thickness_; }
  // The slabs, world frame: one for a plane, one per segment of a path.
  const std::vector<ClipRegion>& regions() const { return regions_; }
  // Drawing coordinates and depth of a world point; `segment`: which slab (0 for a plane).
  Eigen::Vector2d ToDrawing(const Eigen::Vector3d& world, size_t segment, double* depth) const;
  // For a path: the segment a point in several slabs belongs to (nearest in plan).
  size_t NearestSegment(const Eigen::Vector3d& world) const;
  // The world point of drawing coordinates (on the plane; on the path's vertical faces).
  Eigen::Vector3d ToWorld(const Eigen::Vector2d& drawing) const;
  // The plane's normal and in-plane axes (world); for a path, its first segment's.
  Eigen::Vector3d normal() const { return n_[0]; }
  // "plane through (x, y, z) normal (a, b, c), 0.1 m thick" and the like, every digit.
  std::string Describe() const;
  // JSON object: kind, point/normal or vertices, thickness, axes.
  std::string ToJson() const;

 private:
  void AddSegment(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double chainage0, double length);

  double thickness_ = 0;
  bool horizontal_ = false;                 // a plan cut
  std::vector<Eigen::Vector2d> path_;       // plan vertices (path sections)
  std::vector<Eigen::Vector3d> p_, n_, u_, v_;  // per segment: point, unit normal, axes
  std::vector<double> chainage_, length_;   // per segment: chainage at its point, its length
  std::vector<ClipRegion> regions_;
};

}  // namespace candi::section

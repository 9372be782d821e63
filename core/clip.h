// Clipping regions: what `candi render`, `candi view` and `candi section` keep of a cloud.
//
// A region is the intersection of half-spaces, each "the side of a plane its normal points
// into": a point x is kept when (x - point) . normal >= 0 for every plane (on the plane counts as
// inside). A box is six axis-aligned half-spaces (ClipRegion::Box), a slab two (ClipRegion::Slab),
// a half-space one. No plane: everything is kept.
// Frame: whatever frame the points are in; ToLocal moves a world (survey) region into a local
// frame (world = local + origin) in double, so survey coordinates of 1e6-1e7 m keep their mm.
// The test is one expression, evaluated the same way by every renderer (the archive renderer's
// kernel, the in-memory and streaming renderers, the reference), so clipped images stay
// bit-identical between them. Thread-safe (values).
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "core/box.h"

namespace candi {

struct PointCloud;

struct ClipPlane {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // points into the kept side; need not be unit
};

enum class ClipRelation { kInside, kOutside, kPartial };

struct ClipRegion {
  std::vector<ClipPlane> planes;

  bool empty() const { return planes.empty(); }
  bool Contains(const Eigen::Vector3d& x) const {
    for (const ClipPlane& p : planes) {
      if ((x.x() - p.point.x()) * p.normal.x() + (x.y() - p.point.y()) * p.normal.y() +
              (x.z() - p.point.z()) * p.normal.z() < 0) {
        return false;
      }
    }
    return true;
  }
  // Wholly inside (every corner inside every plane), wholly outside (every corner outside one
  // plane) or partial (conservative: a box may be partial and still hold no kept point).
  ClipRelation Classify(const Box3d& box) const;
  // The region in a frame whose origin is `origin` (points x_local = x_world - origin).
  ClipRegion ToLocal(const Eigen::Vector3d& origin) const;
  // This region and `other`'s planes.
  ClipRegion And(const ClipRegion& other) const;

  static ClipRegion Box(const Box3d& box);
  // |(x - point) . n| <= thickness / 2 with n = normal / |normal|.
  static ClipRegion Slab(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double thickness);
  // Throws std::invalid_argument naming `what` for a non-finite value or a zero normal.
  void Check(const std::string& what) const;
  // "px,py,pz,nx,ny,nz; ..." (every digit), or "none": for logs and image metadata.
  std::string Describe() const;
};

// Keeps the points of `cloud` inside `world_region` (world coordinates; the cloud's frame is
// applied); returns how many were removed. No plane: nothing is removed.
size_t ClipCloud(const ClipRegion& world_region, PointCloud* cloud);

// The part of `world` the region's axis-aligned planes keep (the other planes are not applied):
// what a default view frames. `world` itself when nothing would remain.
Box3d ClippedBounds(const Box3d& world, const ClipRegion& region);

// The region's planes as [px, py, pz, nx, ny, nz] each (a message's form; doubles print exactly).
std::vector<std::array<double, 6>> ClipPlaneArrays(const ClipRegion& clip);

}  // namespace candi

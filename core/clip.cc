#include "core/clip.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "core/point_cloud.h"


namespace candi {

ClipRelation ClipRegion::Classify(const Box3d& box) const {
  if (box.IsEmpty()) return ClipRelation::kOutside;
  bool all_inside = true;
  for (const ClipPlane& p : planes) {
    int inside = 0;
    for (int k = 0; k < 8; ++k) {
      const Eigen::Vector3d x(k & 1 ? box.max.x() : box.min.x(), k & 2 ? box.max.y() : box.min.y(),
                              k & 4 ? box.max.z() : box.min.z());
      const ClipRegion one{{p}};
      inside += one.Contains(x) ? 1 : 0;
    }
    if (inside == 0) return ClipRelation::kOutside;
    if (inside < 8) all_inside = false;
  }
  return all_inside ? ClipRelation::kInside : ClipRelation::kPartial;
}

ClipRegion ClipRegion::ToLocal(const Eigen::Vector3d& origin) const {
  ClipRegion local = *this;
  for (ClipPlane& p : local.planes) p.point -= origin;
  return local;
}

ClipRegion ClipRegion::And(const ClipRegion& other) const {
  ClipRegion both = *this;
  both.planes.insert(both.planes.end(), other.planes.begin(), other.planes.end());
  return both;
}

ClipRegion ClipRegion::Box(const Box3d& box) {
  ClipRegion r;
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    n[a] = 1;
    r.planes.push_back({box.min, n});
    r.planes.push_back({box.max, -n});
  }
  return r;
}

ClipRegion ClipRegion::Slab(const Eigen::Vector3d& point, const Eigen::Vector3d& normal, double thickness) {
  const Eigen::Vector3d n = normal.normalized();
  return ClipRegion{{{point - 0.5 * thickness * n, n}, {point + 0.5 * thickness * n, -n}}};
}

void ClipRegion::Check(const std::string& what) const {
  for (size_t k = 0; k < planes.size(); ++k) {
    const ClipPlane& p = planes[k];
    if (!p.point.allFinite() || !p.normal.allFinite()) {
      throw std::invalid_argument(what + ": plane " + std::to_string(k + 1) + " has a non-finite value");
    }
    if (!(p.normal.norm() > 0)) {
      throw std::invalid_argument(what + ": plane " + std::to_string(k + 1) + " has a zero normal");
    }
  }
}

std::string ClipRegion::Describe() const {
  if (planes.empty()) return "none";
  std::string out;
  char text[256];
  for (const ClipPlane& p : planes) {
    std::snprintf(text, sizeof(text), "%s%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", out.empty() ? "" : "; ", p.point.x(),
                  p.point.y(), p.point.z(), p.normal.x(), p.normal.y(), p.normal.z());
    out += text;
  }
  return out;
}

size_t ClipCloud(const ClipRegion& world_region, PointCloud* cloud) {
  if (world_region.empty()) return 0;
  const ClipRegion local = world_region.ToLocal(cloud->frame.origin);
  std::vector<uint8_t> keep(cloud->size());
  for (size_t i = 0; i < keep.size(); ++i) keep[i] = local.Contains(cloud->positions[i]) ? 1 : 0;
  return cloud->Keep(keep);
}

Box3d ClippedBounds(const Box3d& world, const ClipRegion& region) {
  Box3d out = world;
  for (const ClipPlane& p : region.planes) {
    for (int a = 0; a < 3; ++a) {
      const int b = (a + 1) % 3, c = (a + 2) % 3;
      if (p.normal[b] != 0 || p.normal[c] != 0) continue;
      if (p.normal[a] > 0) out.min[a] = std::max(out.min[a], p.point[a]);
      if (p.normal[a] < 0) out.max[a] = std::min(out.max[a], p.point[a]);
    }
  }
  return out.IsEmpty() ? world : out;
}

std::vector<std::array<double, 6>> ClipPlaneArrays(const ClipRegion& clip) {
  std::vector<std::array<double, 6>> out;
  for (const ClipPlane& p : clip.planes) {
    out.push_back({p.point.x(), p.point.y(), p.point.z(), p.normal.x(), p.normal.y(), p.normal.z()});
  }
  return out;
}

}  // namespace candi

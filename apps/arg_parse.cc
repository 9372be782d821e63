#include "apps/arg_parse.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>

namespace candi::app {

std::vector<double> ParseNumbers(const std::string& text, char separator, const std::string& what) {
  std::vector<double> out;
  const char* p = text.data();
  const char* end = p + text.size();
  while (p < end) {
    double v = 0;
    auto [next, ec] = std::from_chars(p, end, v);
    if (ec != std::errc() || !std::isfinite(v)) {
      throw std::invalid_argument(what + " '" + text + "': not a finite number");
    }
    out.push_back(v);
    p = next;
    if (p < end && *p == separator && p + 1 < end) {
      ++p;
    } else if (p < end) {
      throw std::invalid_argument(what + " '" + text + "': unexpected '" + std::string(1, *p) + "'");
    }
  }
  if (out.empty()) throw std::invalid_argument(what + " is empty");
  return out;
}

Eigen::Vector3d ParseDirection(const std::string& text, const std::string& what) {
  const std::vector<double> v = ParseNumbers(text, ',', what);
  if (v.size() != 3) throw std::invalid_argument(what + " '" + text + "': expected x,y,z");
  const Eigen::Vector3d d(v[0], v[1], v[2]);
  if (!(d.norm() > 0) || !d.allFinite()) throw std::invalid_argument(what + " '" + text + "': not a direction");
  return d;
}

ClipRegion ParseClip(const std::string& box, const std::vector<std::string>& planes) {
  ClipRegion region;
  if (!box.empty()) {
    const std::vector<double> v = ParseNumbers(box, ',', "--clip-box");
    if (v.size() != 6) throw std::invalid_argument("--clip-box '" + box + "': expected xmin,ymin,zmin,xmax,ymax,zmax");
    const Box3d b{Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5])};
    if (b.IsEmpty()) throw std::invalid_argument("--clip-box '" + box + "': a minimum exceeds its maximum");
    region = ClipRegion::Box(b);
  }
  for (const std::string& text : planes) {
    const std::vector<double> v = ParseNumbers(text, ',', "--clip-plane");
    if (v.size() != 6) throw std::invalid_argument("--clip-plane '" + text + "': expected px,py,pz,nx,ny,nz");
    const Eigen::Vector3d n(v[3], v[4], v[5]);
    if (!(n.norm() > 0)) throw std::invalid_argument("--clip-plane '" + text + "': the normal is zero");
    region.planes.push_back({Eigen::Vector3d(v[0], v[1], v[2]), n});
  }
  return region;
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

}  // namespace candi::app

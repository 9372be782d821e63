#include "apps/arg_parse.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <stdexcept>

namespace candi::apps {

Eigen::Vector3d ParseDirection(const std::string& text, const std::string& what) {
  const std::vector<double> v = ParseNumbers(text, ',', what);
  if (v.size() != 3) throw std::invalid_argument(what + " '" + text + "': expected x,y,z");
  const Eigen::Vector3d d(v[0], v[1], v[2]);
  if (!(d.norm() > 0) || !d.allFinite()) throw std::invalid_argument(what + " '" + text + "': not a direction");
  return d;
}

void ParseSize(const std::string& text, const std::string& what, int* width, int* height) {
  const std::vector<double> v = ParseNumbers(text, 'x', what);
  if (v.size() != 2 || v[0] < 1 || v[1] < 1 || v[0] > 16384 || v[1] > 16384 || v[0] != std::floor(v[0]) ||
      v[1] != std::floor(v[1])) {
    throw std::invalid_argument(what + " '" + text + "': expected WxH, whole pixels in [1, 16384]");
  }
  *width = static_cast<int>(v[0]);
  *height = static_cast<int>(v[1]);
}

Rgb8 ParseColour(const std::string& text, const std::string& what) {
  const std::vector<double> v = ParseNumbers(text, ',', what);
  for (double c : v) {
    if (v.size() != 3 || c < 0 || c > 255 || c != std::floor(c)) {
      throw std::invalid_argument(what + " '" + text + "': expected r,g,b, each 0..255");
    }
  }
  if (v.size() != 3) throw std::invalid_argument(what + " '" + text + "': expected r,g,b");
  return {static_cast<uint8_t>(v[0]), static_cast<uint8_t>(v[1]), static_cast<uint8_t>(v[2])};
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

}  // namespace candi::apps

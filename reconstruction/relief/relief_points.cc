#include "reconstruction/relief/relief_points.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/check.h"
#include "reconstruction/relief/relief_image.h"

namespace candi::relief {

void ReliefPointsOptions::Check() const {
  CANDI_CHECK_OPTION(width_m > 0 && std::isfinite(width_m), width_m, "a finite number > 0");
  CANDI_CHECK_OPTION(height_m > 0 && std::isfinite(height_m), height_m, "a finite number > 0");
  CANDI_CHECK_OPTION(depth_m > 0 && std::isfinite(depth_m), depth_m, "a finite number > 0");
}

PointCloud DepthToPoints(const ReliefPointsOptions& o, const ImageF& photo, const ImageF& depth) {
  o.Check();
  CANDI_CHECK(photo.channels() == 1 && depth.channels() == 1);
  CANDI_CHECK(photo.width() == depth.width() && photo.height() == depth.height())
      << "photo " << photo.width() << "x" << photo.height() << ", depth " << depth.width() << "x"
      << depth.height();
  const int w = depth.width(), h = depth.height();
  PointCloud cloud;
  cloud.schema.colors = true;
  cloud.schema.position_type = ScalarType::kFloat32;  // millimetres at metre scale: float is plenty
  cloud.SetSchema(cloud.schema);
  cloud.Resize(static_cast<size_t>(w) * h);
  const double sx = o.width_m / w, sy = o.height_m / h;
  for (int j = 0; j < h; ++j) {
    const double y = o.height_m - (j + 0.5) * sy;
    for (int i = 0; i < w; ++i) {
      const size_t k = static_cast<size_t>(j) * w + i;
      const float level = depth.values()[k];
      const double z = std::isfinite(level) ? HeightFromLevel(std::clamp<double>(level, 0, kMaxLevel), o.depth_m) : 0.0;
      cloud.positions[k] = Eigen::Vector3d((i + 0.5) * sx, y, z);
      const float g = photo.values()[k];
      const auto v = static_cast<uint8_t>(std::lround(255.0f * (std::isfinite(g) ? std::clamp(g, 0.0f, 1.0f) : 0.0f)));
      cloud.colors[k] = {v, v, v};
    }
  }
  return cloud;
}

}  // namespace candi::relief

#include "render/zbuffer.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "core/check.h"

namespace candi::render {

Image8 RenderOpaque(const OpaqueRenderOptions& options, const Camera& camera, const PointCloud& cloud) {
  CANDI_CHECK(cloud.size() < (1ull << 32)) << "RenderOpaque keeps 32-bit indices";
  const Camera::Projector projector = camera.MakeProjector();
  const int w = camera.width, h = camera.height;
  // Key: float depth bits (monotone for positive floats) in the high word, index in the low word.
  std::vector<uint64_t> key(static_cast<size_t>(w) * h, std::numeric_limits<uint64_t>::max());
  for (size_t i = 0; i < cloud.size(); ++i) {
    double u, v, depth;
    if (!projector.Project(cloud.positions[i], &u, &v, &depth)) continue;
    const double fu = std::floor(u), fv = std::floor(v);
    if (fu < 0 || fv < 0 || fu >= w || fv >= h) continue;
    const float d = static_cast<float>(std::max(depth, 0.0));
    uint32_t bits;
    std::memcpy(&bits, &d, 4);
    const uint64_t k = (static_cast<uint64_t>(bits) << 32) | static_cast<uint32_t>(i);
    uint64_t& slot = key[static_cast<size_t>(fv) * w + static_cast<size_t>(fu)];
    if (k < slot) slot = k;
  }
  Image8 image(w, h, 3);
  for (size_t p = 0; p < key.size(); ++p) {
    Rgb8 c = options.background;
    if (key[p] != std::numeric_limits<uint64_t>::max()) {
      const size_t i = static_cast<uint32_t>(key[p]);
      c = cloud.schema.colors ? cloud.colors[i] : options.default_color;
    }
    image.data()[3 * p] = c.r;
    image.data()[3 * p + 1] = c.g;
    image.data()[3 * p + 2] = c.b;
  }
  return image;
}

}  // namespace candi::render

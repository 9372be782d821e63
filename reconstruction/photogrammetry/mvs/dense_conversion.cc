// The pure half of dense_workspace.h: struct filling between COLMAP's model types and candi's
// stereo types (no file access, so it links without colmap_model.cc).
#include <cmath>
#include <string>

#include "core/check.h"
#include "reconstruction/photogrammetry/mvs/dense_workspace.h"

namespace candi::photogrammetry {

PinholeCamera ToPinholeCamera(const ColmapCamera& camera, const ColmapImage& image,
                              const std::string& source) {
  PinholeCamera c;
  c.width = camera.width;
  c.height = camera.height;
  const auto& p = camera.params;
  if (camera.model == "PINHOLE" && p.size() == 4) {
    c.fx = p[0], c.fy = p[1], c.cx = p[2], c.cy = p[3];
  } else if (camera.model == "SIMPLE_PINHOLE" && p.size() == 3) {
    c.fx = c.fy = p[0], c.cx = p[1], c.cy = p[2];
  } else {
    throw InputError(source, "camera " + std::to_string(camera.camera_id),
                     "model " + camera.model + " with " + std::to_string(p.size()) +
                         " parameters; dense stereo needs undistorted PINHOLE or SIMPLE_PINHOLE "
                         "cameras (run `colmap image_undistorter`, or `candi sfm`)");
  }
  if (!c.Valid() || !std::isfinite(c.cx) || !std::isfinite(c.cy))
    throw InputError(source, "camera " + std::to_string(camera.camera_id),
                     "invalid size or focal length");
  c.rotation = image.cam_from_world_rotation.normalized().toRotationMatrix();
  c.translation = image.cam_from_world_translation;
  if (!c.rotation.allFinite() || !c.translation.allFinite())
    throw InputError(source, "image " + std::to_string(image.image_id), "non-finite pose");
  return c;
}

namespace {
ColmapArray ToArray(const ImageF& image) {
  ColmapArray a;
  a.width = image.width(), a.height = image.height(), a.channels = image.channels();
  a.data.resize(image.values().size());
  for (int c = 0; c < a.channels; ++c)
    for (int y = 0; y < a.height; ++y)
      for (int x = 0; x < a.width; ++x) a.at(x, y, c) = image.at(x, y, c);
  return a;
}
}  // namespace

ColmapArray DepthArray(const DepthNormalMap& map) { return ToArray(map.depth); }
ColmapArray NormalArray(const DepthNormalMap& map) { return ToArray(map.normal); }

}  // namespace candi::photogrammetry

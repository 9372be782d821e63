#include "apps/view_orientation.h"

#include <stdexcept>

#include "apps/arg_parse.h"
#include "core/check.h"
#include "core/log.h"
#include "reconstruction/photogrammetry/colmap_model.h"

namespace candi::app {

view::Orientation ParseOrientation(const std::string& up, const std::string& from, const std::string& cameras) {
  view::Orientation o;
  if (!cameras.empty()) {
    const photogrammetry::ColmapModel model = photogrammetry::ReadColmapModel(cameras);
    Eigen::Vector3d down = Eigen::Vector3d::Zero(), forward = Eigen::Vector3d::Zero();
    for (const auto& [id, image] : model.images) {
      const Eigen::Matrix3d world_from_cam = image.cam_from_world_rotation.toRotationMatrix().transpose();
      down += world_from_cam.col(1);
      forward += world_from_cam.col(2);
    }
    if (model.images.empty() || !(down.norm() > 1e-6 * model.images.size())) {
      throw InputError(cameras, "", "no registered images (or their up directions cancel out): cannot orient a view");
    }
    o.up = -down.normalized();
    // Looking the cameras' way, tilted to be square to up (an oblique mean would tilt the view).
    const Eigen::Vector3d level = forward - forward.dot(o.up) * o.up;
    if (level.norm() > 1e-6 * std::max(1.0, forward.norm())) o.view_dir = level.normalized();
    LogInfo("view oriented by the " + std::to_string(model.images.size()) + " cameras of " + cameras);
  }
  if (!up.empty()) o.up = ParseDirection(up, "--up");
  if (!from.empty()) o.view_dir = ParseDirection(from, "--from");
  return o;
}

}  // namespace candi::app

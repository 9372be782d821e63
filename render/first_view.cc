#include "render/first_view.h"

#include <Eigen/Geometry>
#include <cmath>
#include <stdexcept>

namespace candi::render {

Camera FirstView(const Box3d& world_bounds, int width, int height, const Orientation& o) {
  if (!(o.up.norm() > 0) || !o.up.allFinite()) throw std::invalid_argument("the up direction is not a direction");
  const Eigen::Vector3d up = o.up.normalized();
  if (o.view_dir && !(o.view_dir->norm() > 0 && o.view_dir->normalized().cross(up).norm() > 1e-3)) {
    throw std::invalid_argument("the viewing direction (--from) is zero or parallel to up (--up): the view would "
                                "have no up");
  }
  // candi render's default (from above, oblique) turned from z-up to `up`.
  const Eigen::Vector3d dir = o.view_dir ? *o.view_dir
                                         : Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), up) *
                                               Eigen::Vector3d(0.45, 0.7, -0.55);
  Camera c = FrameBox(world_bounds, width, height, dir);
  if (std::abs(dir.normalized().dot(up)) < 0.999) c.up = up;
  return c;
}

}  // namespace candi::render

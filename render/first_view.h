// The default view of data nobody has chosen a view of: from above and obliquely, framing the
// data's bounds, turned to the data's up (survey data: z; a COLMAP model's frame: -y, or its
// cameras' mean up). `candi render` without --view, `candi view`'s first view, scene views
// without a camera.
#pragma once

#include <Eigen/Core>
#include <optional>

#include "core/box.h"
#include "render/camera.h"

namespace candi::render {

// Where "up" is and which side the first view looks from.
struct Orientation {
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();     // world up (survey data: z)
  std::optional<Eigen::Vector3d> view_dir;           // eye -> target; default: from above, oblique
};

// A camera that frames `world_bounds` (world frame) for `orientation`. Throws
// std::invalid_argument when up is not a direction or the viewing direction is parallel to it.
Camera FirstView(const Box3d& world_bounds, int width, int height, const Orientation& orientation);

}  // namespace candi::render

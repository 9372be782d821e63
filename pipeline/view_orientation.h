// The default view's orientation as a command asks for it (--cameras, --up, --from of candi
// render, view and publish): up and side from the cameras of a COLMAP model whose frame the points
// are in, and directions given over them. World frame. Failures: InputError for a model that
// cannot be read (OrientationOfCameras).
#pragma once

#include <Eigen/Core>

#include <optional>
#include <string>

#include "render/first_view.h"

namespace candi::pipeline {

struct ViewOrientation {
  std::string cameras;                // a COLMAP model (e.g. WORK/sparse/0); "": none
  std::optional<Eigen::Vector3d> up;  // world up, non-zero; none: the cameras' (else +z)
  // The direction the view looks in, non-zero; none: the cameras' (else oblique, from above).
  std::optional<Eigen::Vector3d> view_dir;
  // The cameras' orientation (OrientationOfCameras; the default one without a model), with
  // `up` and `view_dir` where given. Reads the model each call.
  render::Orientation Resolve() const;
};

}  // namespace candi::pipeline

#include "pipeline/view_orientation.h"

#include "pipeline/render.h"

namespace candi::pipeline {

render::Orientation ViewOrientation::Resolve() const {
  render::Orientation o = cameras.empty() ? render::Orientation() : OrientationOfCameras(cameras);
  if (up) o.up = *up;
  if (view_dir) o.view_dir = *view_dir;
  return o;
}

}  // namespace candi::pipeline

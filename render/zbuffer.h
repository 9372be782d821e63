// Opaque point rendering with a per-pixel z-buffer: each pixel shows its nearest point.
// One-pixel points; ties in depth are broken by the lower point index, so the image does not
// depend on the order of work. This is SPBR with one ensemble (L = 1).
#pragma once

#include "core/image.h"
#include "core/point_cloud.h"
#include "render/camera.h"

namespace candi::render {

struct OpaqueRenderOptions {
  Rgb8 background{255, 255, 255};
  Rgb8 default_color{128, 128, 128};  // for clouds without colours
};

// Renders cloud (positions in its local frame, which the camera shares) into an RGB image.
Image8 RenderOpaque(const OpaqueRenderOptions& options, const Camera& camera, const PointCloud& cloud);

}  // namespace candi::render

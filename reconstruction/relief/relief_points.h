// A predicted depth map to metric points of the carved panel.
//
// One point per pixel, in the panel frame (metres): x along the wall from the panel's left edge,
// y up from its bottom edge, z out of the wall (the wall is z = 0). Pixel (i, j) of a W x H image
// (row j from the top) becomes x = (i + 0.5) width_m / W, y = height_m - (j + 0.5) height_m / H,
// z = depth_m (1 - level / 255) (levels as in relief_image.h); its colour is the photo's grey.
// A non-finite level is placed on the wall (z = 0). Thread-safe.
#pragma once

#include "core/image.h"
#include "core/point_cloud.h"
#include "reconstruction/relief/panel_size.h"

namespace candi::relief {

struct ReliefPointsOptions {
  double width_m = kPanelWidthM;    // panel width, m, > 0
  double height_m = kPanelHeightM;  // panel height, m, > 0
  double depth_m = kPanelDepthM;    // depth of level 0 above the wall (level 255), m, > 0
  void Check() const;      // throws std::invalid_argument naming the field
};

// photo: grey [0, 1]; depth: levels; same size, one channel each (CANDI_CHECK).
PointCloud DepthToPoints(const ReliefPointsOptions& options, const ImageF& photo,
                         const ImageF& depth);

}  // namespace candi::relief

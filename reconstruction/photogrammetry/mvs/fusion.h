// Fusion of depth and normal maps into one coloured point cloud with normals (candi's own, in the
// spirit of COLMAP's StereoFusion): every valid pixel not yet used seeds a point; its 3D point is
// projected into every other view, and the pixel it lands on joins when that view's depth agrees
// (relative tolerance), its normal agrees (angle) and it reprojects within a pixel tolerance.
// Points seen by at least `min_views` views are kept: mean position, mean colour, mean normal.
//
// Frames: positions in the model frame of the cameras (a LocalFrame at the origin); normals world-
// frame unit vectors. Deterministic (views and pixels in a fixed order). Not parallel.
#pragma once

#include <vector>

#include "core/point_cloud.h"
#include "core/progress.h"
#include "reconstruction/photogrammetry/mvs/patch_match.h"

namespace candi::photogrammetry {

struct FusionOptions {
  int min_views = 3;                 // views agreeing on a point (the seed included), >= 1
  double max_depth_error = 0.01;     // |d' - d| / d, > 0
  double max_normal_error_deg = 20;  // angle between normals, degrees, in (0, 180]
  double max_reprojection_error_px = 2;  // pixels, > 0
  void Check() const;
};

PointCloud FuseDepthMaps(const FusionOptions& options, const std::vector<DepthNormalMap>& maps,
                         const ProgressCallback& progress = nullptr);

}  // namespace candi::photogrammetry

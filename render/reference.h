// Reference renderers that SPBR is compared with: what a user would otherwise use.
//
// Every point is a one-pixel fragment with opacity alpha = m / L (m: its multiplicity, 1 without
// opacity control; L: the repeat level), which is the opacity SPBR gives it.
//  - RenderSortedBlend: exact per-pixel front-to-back alpha blending of the depth-sorted
//    fragments, C = sum_k a_k prod_{j<k} (1 - a_j) C_k + prod (1 - a_j) background. This is the
//    expected value of the SPBR image (ALGORITHMS.md §1), the ground truth of the accuracy tests.
//    O(N log N) per view.
//  - RenderWeightedOit: weighted blended order-independent transparency (McGuire and Bavoil,
//    JCGT 2013, weight of their eq. 10 on the fragments' normalised depth): one pass, no sort,
//    approximate.
// The camera is in `frame` (use the SplatCloud's frame to compare with SPBR).
#pragma once

#include <vector>

#include "core/image.h"
#include "core/local_frame.h"
#include "core/point_cloud.h"
#include "core/spbr_settings.h"
#include "render/camera.h"

namespace candi::render {

struct ReferenceOptions {
  SpbrSettings spbr;             // L (1 when opaque) and its multiplicities (point size: 1)
  bool use_multiplicity = true;  // honour `spbr_multiplicity` (not when spbr.opaque)
  Rgb8 background{0, 0, 0};
  Rgb8 default_color{200, 200, 200};  // for clouds without colours
  void Check() const;
};

ImageF RenderSortedBlend(const ReferenceOptions& options, const Camera& camera,
                         const LocalFrame& frame, const std::vector<const PointCloud*>& clouds);
ImageF RenderWeightedOit(const ReferenceOptions& options, const Camera& camera,
                         const LocalFrame& frame, const std::vector<const PointCloud*>& clouds);

// Root-mean-square difference of two images of the same size (all channels), grey levels.
double Rmse(const ImageF& a, const ImageF& b);

}  // namespace candi::render

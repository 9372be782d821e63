// A dense cloud scored against a synthetic scene's true surface, at distance tolerances (as the
// ETH3D and Tanks and Temples benchmarks score MVS): accuracy = the share of the points within
// tau of the surface, completeness = the share of the surface within tau of a point, F-score =
// their harmonic mean.
//  - A point's distance to the surface: along the ray of each view it projects into, the
//    difference between its distance from the camera and the true surface's there (the true
//    depth of that pixel); the least over the views. For a surface seen face-on this is the
//    distance to it; seen at a slant it is more, so the accuracy is, if anything, understated.
//  - The surface: every `stride`-th pixel of every view's true depth, back-projected.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "reconstruction/photogrammetry/scenes/synthetic_views.h"

namespace candi::photogrammetry {

struct DenseTruthScore {
  double tau = 0;  // metres
  double accuracy = 0, completeness = 0, f_score = 0;  // [0, 1]
};

// One score per tolerance (in order); parallel, deterministic. Non-finite points count as wrong.
std::vector<DenseTruthScore> ScoreDenseAgainstTruth(const std::vector<SyntheticView>& views,
                                                    const std::vector<Eigen::Vector3d>& points,
                                                    const std::vector<double>& taus, int stride = 2);

}  // namespace candi::photogrammetry

// A synthetic scene's views as a COLMAP dense workspace, for tests and benchmarks of the stages
// that read one (candi dense, the demo): the cameras are the truth, no SfM is run.
#pragma once

#include <string>
#include <vector>

#include "reconstruction/photogrammetry/scenes/synthetic_views.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"

namespace candi::photogrammetry {

// A model with one PINHOLE camera per view, image ids 1..N in order, and `points` as points3D
// (grey), each with a track of the views where it is the visible surface (in the image, within
// 1 % of the view's true depth there), as SfM would have observed it.
ColmapModel ToColmapModel(const std::vector<SyntheticView>& views,
                          const std::vector<Eigen::Vector3d>& points);

// Writes images/ (PNG) and sparse/ (binary model) for known cameras, e.g. the synthetic scene.
void WriteDenseWorkspace(const std::vector<SyntheticView>& views,
                         const std::vector<Eigen::Vector3d>& points, const std::string& workspace);

}  // namespace candi::photogrammetry

// The glue between COLMAP sparse models (colmap_model.h) and georeferencing, kept in one file so
// `candi georef` touches COLMAP's formats nowhere else.
//
// Cameras: each registered image becomes a projection matrix P = K [R | t] (model frame, COLMAP's
// pixel convention). Only pinhole cameras are accepted (SIMPLE_PINHOLE, PINHOLE, or a distortion
// model whose distortion parameters are all zero): picks belong in undistorted images, e.g. the
// images and model COLMAP's image_undistorter writes. Failure: InputError naming the folder.
#pragma once

#include <map>
#include <string>

#include "core/point_cloud.h"
#include "core/transform.h"
#include "reconstruction/photogrammetry/georef/georef.h"

namespace candi::photogrammetry {

struct ColmapGeorefInput {
  std::map<std::string, ProjectionMatrix> cameras;  // by image name
  PointCloud points;                                // the sparse points with colours, model frame
};

// Reads DIR (a COLMAP sparse model, .bin or .txt).
ColmapGeorefInput ReadColmapForGeoref(const std::string& sparse_dir);

// Writes the model of `sparse_dir` transformed into `local_from_model` (the survey frame minus the
// shift, so the coordinates stay small) to `out_dir` (binary), cameras re-posed accordingly.
void WriteGeoreferencedColmapModel(const std::string& sparse_dir, const Sim3& local_from_model,
                                   const std::string& out_dir);

}  // namespace candi::photogrammetry

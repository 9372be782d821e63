// COLMAP dense workspaces for candi's PatchMatch: WORKSPACE/images/ (undistorted images),
// WORKSPACE/sparse/ (a COLMAP model with PINHOLE or SIMPLE_PINHOLE cameras), and
// WORKSPACE/stereo/{depth_maps,normal_maps}/NAME.geometric.bin (COLMAP arrays) that COLMAP's
// stereo_fusion reads.
//
// The conversions (model <-> cameras, maps <-> arrays) are pure; the readers and writers use
// colmap_model.h. Failures: a missing or unreadable image, a camera model with distortion, or an
// image whose size differs from its camera throw InputError naming the file.
#pragma once

#include <string>
#include <vector>

#include "reconstruction/photogrammetry/mvs/patch_match.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"

namespace candi::photogrammetry {

// --- pure conversions -------------------------------------------------------------------------

// A PINHOLE or SIMPLE_PINHOLE camera with the image's pose; InputError (naming `source`) otherwise.
PinholeCamera ToPinholeCamera(const ColmapCamera& camera, const ColmapImage& image,
                              const std::string& source);
// Depth map (1 channel) and normal map (3 channels) in COLMAP's array layout.
ColmapArray DepthArray(const DepthNormalMap& map);
ColmapArray NormalArray(const DepthNormalMap& map);

// --- files (need colmap_model.cc) -----------------------------------------------------------

// Reads WORKSPACE/sparse and every image of the model from WORKSPACE/images (any format OpenCV
// reads), in image-id order; the model's points become the sparse points.
StereoInput ReadDenseWorkspace(const std::string& workspace);
// Writes WORKSPACE/stereo/{depth_maps,normal_maps}/<name>.geometric.bin, one per map (atomic).
void WriteDepthNormalMaps(const std::vector<DepthNormalMap>& maps,
                          const std::vector<std::string>& names, const std::string& workspace);

}  // namespace candi::photogrammetry

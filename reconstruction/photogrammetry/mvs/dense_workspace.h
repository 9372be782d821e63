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

// Reads WORKSPACE/sparse: the images' names and cameras (no pixels) in image-id order, the
// model's points and, per point, the images of its track (empty when no point has a track).
StereoInput ReadDenseModel(const std::string& workspace);
// ReadDenseModel and every image from WORKSPACE/images (any format OpenCV reads).
StereoInput ReadDenseWorkspace(const std::string& workspace);
// One image of WORKSPACE/images, checked against its camera's size (InputError naming the file).
Image8 ReadStereoImage(const std::string& workspace, const StereoImage& image);

// candi's depth-map file (WORKSPACE/stereo/candi/): "CANDIDM1", u32 width, height, source count,
// flags (1: cost, 2: colour), u64 pixels with a depth, the sources (i32), then depth (f32), normal (3 x f32, interleaved),
// cost (f32) and colour (3 x u8) at width x height, little-endian. Written atomically, so a file
// that is there is complete; a reader finding anything else throws InputError naming the file.
void WriteDepthMapFile(const DepthNormalMap& map, bool with_cost, const std::string& path);
// The pixels with a depth, from the header, after checking it and the file's size against the
// camera (InputError naming the file otherwise): a finished map, without reading it.
uint64_t DepthMapFileValidPixels(const std::string& path, const PinholeCamera& camera);
// Creates the folder a file goes in (and its parents); InputError naming it when that fails.
void CreateParentFolder(const std::string& path);
// `camera` is the map's camera at the working resolution (not stored); its size must match.
DepthNormalMap ReadDepthMapFile(const std::string& path, const PinholeCamera& camera);
// Writes WORKSPACE/stereo/{depth_maps,normal_maps}/<name>.geometric.bin, one per map (atomic).
void WriteDepthNormalMaps(const std::vector<DepthNormalMap>& maps,
                          const std::vector<std::string>& names, const std::string& workspace);

}  // namespace candi::photogrammetry

// COLMAP sparse models (cameras, images, points3D) and dense-workspace arrays (depth and normal
// maps), read and written natively in both of COLMAP's formats (binary .bin and text .txt), as
// COLMAP 3.8 writes them.
//
// Frames and conventions are COLMAP's: each image stores cam_from_world (a Hamilton unit quaternion
// qw qx qy qz and a translation, metres in the model's frame); a pixel centre is at (x + 0.5, y + 0.5)
// in COLMAP's image coordinates. Camera parameters follow COLMAP's model definitions (SIMPLE_PINHOLE:
// f cx cy; PINHOLE: fx fy cx cy; SIMPLE_RADIAL: f cx cy k; RADIAL: f cx cy k1 k2; OPENCV:
// fx fy cx cy k1 k2 p1 p2; ...).
//
// Failure: a missing, truncated or malformed file throws candi::InputError naming the file and the
// byte offset (binary) or line (text).
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace candi::photogrammetry {

struct ColmapCamera {
  uint32_t camera_id = 0;
  std::string model;           // "PINHOLE", "SIMPLE_RADIAL", ... (COLMAP's names)
  int width = 0, height = 0;   // pixels
  std::vector<double> params;  // in COLMAP's order for the model
};

struct ColmapImage {
  uint32_t image_id = 0;
  Eigen::Quaterniond cam_from_world_rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d cam_from_world_translation = Eigen::Vector3d::Zero();
  uint32_t camera_id = 0;
  std::string name;                     // path relative to the image folder
  std::vector<Eigen::Vector2d> points2d;  // pixels
  std::vector<uint64_t> point3d_ids;      // one per points2d; kInvalidPoint3dId when untriangulated
};

constexpr uint64_t kInvalidPoint3dId = static_cast<uint64_t>(-1);

struct ColmapTrackElement {
  uint32_t image_id = 0;
  uint32_t point2d_idx = 0;
};

struct ColmapPoint3d {
  uint64_t point3d_id = 0;
  Eigen::Vector3d xyz = Eigen::Vector3d::Zero();  // model frame
  std::array<uint8_t, 3> rgb{};
  double error = 0;  // mean reprojection error, pixels
  std::vector<ColmapTrackElement> track;
};

struct ColmapModel {
  std::map<uint32_t, ColmapCamera> cameras;
  std::map<uint32_t, ColmapImage> images;
  std::map<uint64_t, ColmapPoint3d> points3d;
};

// Reads DIR/{cameras,images,points3D}.bin, or the .txt files when the .bin are absent.
ColmapModel ReadColmapModel(const std::string& dir);
// Writes the three files into DIR (created if missing), each atomically (temporary + rename).
void WriteColmapModelBinary(const ColmapModel& model, const std::string& dir);
void WriteColmapModelText(const ColmapModel& model, const std::string& dir);

// A dense-workspace array (depth map: 1 channel; normal map: 3 channels), COLMAP's format: an ASCII
// header "W&H&C&" then W*H*C little-endian float32 stored channel-planar (all of channel 0, then 1...).
struct ColmapArray {
  int width = 0, height = 0, channels = 0;
  std::vector<float> data;  // channel-planar, row-major: data[(c * height + y) * width + x]
  float& at(int x, int y, int c = 0) { return data[(static_cast<size_t>(c) * height + y) * width + x]; }
  float at(int x, int y, int c = 0) const {
    return data[(static_cast<size_t>(c) * height + y) * width + x];
  }
};
ColmapArray ReadColmapArray(const std::string& path);
void WriteColmapArray(const ColmapArray& array, const std::string& path);  // atomic

// COLMAP 3.8's camera models: id (as stored in cameras.bin) <-> name, and parameter count.
// CameraModelId returns -1 and CameraModelNumParams 0 for an unknown name; CameraModelName returns
// "" for an unknown id.
int CameraModelId(const std::string& name);
std::string CameraModelName(int id);
int CameraModelNumParams(const std::string& name);

// Projects a world point (model frame) to COLMAP image coordinates (pixels, the top-left image
// corner at (0, 0), so a pixel centre is at (x + 0.5, y + 0.5)), exactly as COLMAP does:
// x_cam = R(q) X + t with q normalized, (u, v) = x_cam.xy / x_cam.z, distortion, then focal and
// principal point. Supports SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV and
// FULL_OPENCV; other models throw std::invalid_argument. A point behind the camera (z <= 0)
// projects to NaN.
Eigen::Vector2d ProjectToImage(const ColmapCamera& camera, const ColmapImage& image,
                               const Eigen::Vector3d& world_point);

// COLMAP's mean reprojection error of a model: the mean of the points' stored errors (points with
// COLMAP's "no error" value -1 skipped); 0 for a model without points. Pixels.
double MeanReprojectionError(const ColmapModel& model);

}  // namespace candi::photogrammetry

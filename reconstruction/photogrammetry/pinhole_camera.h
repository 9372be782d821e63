// PinholeCamera: an undistorted pinhole camera (COLMAP's PINHOLE model) with its pose.
//
// Conventions are COLMAP's: cam_from_world maps world points into the camera frame (x right,
// y down, z forward, metres); a pixel centre is at (x + 0.5, y + 0.5) in image coordinates; depth is
// the camera-frame z (what COLMAP's depth maps store). Plain value type, thread-safe to read.
#pragma once

#include <Eigen/Core>

namespace candi::photogrammetry {

struct PinholeCamera {
  int width = 0, height = 0;                              // pixels
  double fx = 0, fy = 0, cx = 0, cy = 0;                  // pixels
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  // cam_from_world R
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();   // cam_from_world t

  Eigen::Vector3d Center() const { return -rotation.transpose() * translation; }
  Eigen::Vector3d ToCamera(const Eigen::Vector3d& world) const { return rotation * world + translation; }
  Eigen::Vector3d ToWorld(const Eigen::Vector3d& cam) const {
    return rotation.transpose() * (cam - translation);
  }
  // Image coordinates (continuous; pixel (x, y) spans [x, x + 1)) of a camera-frame point, z > 0.
  Eigen::Vector2d Project(const Eigen::Vector3d& cam) const {
    return {fx * cam.x() / cam.z() + cx, fy * cam.y() / cam.z() + cy};
  }
  // The camera-frame ray through image coordinates (u, v), scaled to z = 1.
  Eigen::Vector3d Ray(double u, double v) const { return {(u - cx) / fx, (v - cy) / fy, 1.0}; }
  // The same camera for an image resampled by `scale` (new size = round(old size * scale)).
  PinholeCamera Scaled(double scale) const;
  bool Valid() const { return width > 0 && height > 0 && fx > 0 && fy > 0; }
};

inline PinholeCamera PinholeCamera::Scaled(double scale) const {
  PinholeCamera c = *this;
  c.width = static_cast<int>(width * scale + 0.5);
  c.height = static_cast<int>(height * scale + 0.5);
  const double sx = static_cast<double>(c.width) / width, sy = static_cast<double>(c.height) / height;
  c.fx *= sx;
  c.cx *= sx;
  c.fy *= sy;
  c.cy *= sy;
  return c;
}

}  // namespace candi::photogrammetry

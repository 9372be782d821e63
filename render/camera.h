// Camera: a pinhole (perspective) or orthographic view of the local frame.
//
// Camera frame (OpenCV convention): x right, y down, z forward (viewing direction). Pixel (0, 0)
// is the top-left corner of the top-left pixel; a point projects to continuous pixel coordinates
// (u, v). The world frame is z-up; `up` orients the image. Units: metres, degrees for the field
// of view. Thread-safe for const use.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/box.h"

namespace candi::render {

enum class Projection { kPerspective, kOrthographic };

struct Camera {
  Projection projection = Projection::kPerspective;
  int width = 1024;                 // pixels, >= 1
  int height = 768;                 // pixels, >= 1
  Eigen::Vector3d eye = Eigen::Vector3d(0, -10, 0);  // local frame, m
  Eigen::Vector3d target = Eigen::Vector3d::Zero();  // local frame, m
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();     // world up, not parallel to target - eye
  double fov_y_deg = 40.0;          // perspective: vertical field of view, (0, 180)
  double ortho_height = 10.0;       // orthographic: visible height in metres, > 0
  double near = 1e-3;               // points closer than this (m, along the view axis) are culled

  // Throws std::invalid_argument naming the field.
  void Check() const;

  // Rotation rows of camera_from_world and the focal length in pixels (perspective) or pixels
  // per metre (orthographic). Call after changing any field.
  struct Projector {
    Eigen::Matrix3d rotation;  // camera_from_local rotation
    Eigen::Vector3d eye;
    double focal;
    double cx, cy;
    bool perspective;
    double near;
    // Projects a local point; false when behind the near plane. depth = distance along the axis.
    bool Project(const Eigen::Vector3d& x, double* u, double* v, double* depth) const {
      const Eigen::Vector3d c = rotation * (x - eye);
      if (c.z() < near) return false;
      const double s = perspective ? focal / c.z() : focal;
      *u = cx + s * c.x();
      *v = cy + s * c.y();
      *depth = c.z();
      return true;
    }
  };
  Projector MakeProjector() const;

  // Size in metres of one pixel's footprint at `depth` (the point cross-section s of SPBR).
  double PixelFootprint(double depth) const;
};

// A camera that frames `box` (local frame) from direction `view_dir` (from the eye towards the
// box), with a small margin.
Camera FrameBox(const Box3d& box, int width, int height, const Eigen::Vector3d& view_dir,
                Projection projection = Projection::kPerspective, double fov_y_deg = 40.0);

// Orthographic views: what every depth is shifted by so that the depths of points within
// `bounds` are positive, as the splat kernel's keys need (1 - the nearest corner's depth, or 0);
// 0 for perspective views.
double OrthographicDepthOffset(const Camera::Projector& projector, const Box3d& bounds);

}  // namespace candi::render

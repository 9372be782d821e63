#include "render/camera.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace candi::render {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

void Camera::Check() const {
  if (width < 1 || height < 1) {
    throw std::invalid_argument("Camera::width/height = " + std::to_string(width) + "x" +
                                std::to_string(height) + "; must be >= 1");
  }
  if (!eye.allFinite() || !target.allFinite() || !up.allFinite()) {
    throw std::invalid_argument("Camera::eye/target/up must be finite");
  }
  const Eigen::Vector3d forward = target - eye;
  if (!(forward.norm() > 0)) throw std::invalid_argument("Camera::target equals Camera::eye");
  if (forward.normalized().cross(up.normalized()).norm() < 1e-9) {
    throw std::invalid_argument("Camera::up is parallel to the viewing direction");
  }
  if (projection == Projection::kPerspective && !(fov_y_deg > 0 && fov_y_deg < 180)) {
    throw std::invalid_argument("Camera::fov_y_deg = " + std::to_string(fov_y_deg) + "; must be in (0, 180)");
  }
  if (projection == Projection::kOrthographic && !(ortho_height > 0)) {
    throw std::invalid_argument("Camera::ortho_height = " + std::to_string(ortho_height) + "; must be > 0");
  }
  if (!(near > 0) && projection == Projection::kPerspective) {
    throw std::invalid_argument("Camera::near = " + std::to_string(near) + "; must be > 0");
  }
}

Camera::Projector Camera::MakeProjector() const {
  Check();
  Projector p;
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = z.cross(up).normalized();  // right
  const Eigen::Vector3d y = z.cross(x);                 // down
  p.rotation.row(0) = x.transpose();
  p.rotation.row(1) = y.transpose();
  p.rotation.row(2) = z.transpose();
  p.eye = eye;
  p.perspective = projection == Projection::kPerspective;
  p.focal = p.perspective ? 0.5 * height / std::tan(0.5 * fov_y_deg * kPi / 180.0)
                          : height / ortho_height;
  p.cx = 0.5 * width;
  p.cy = 0.5 * height;
  p.near = p.perspective ? near : -std::numeric_limits<double>::infinity();
  return p;
}

double Camera::PixelFootprint(double depth) const {
  const Projector p = MakeProjector();
  return p.perspective ? depth / p.focal : 1.0 / p.focal;
}

Camera FrameBox(const Box3d& box, int width, int height, const Eigen::Vector3d& view_dir,
                Projection projection, double fov_y_deg) {
  Camera camera;
  camera.projection = projection;
  camera.width = width;
  camera.height = height;
  camera.fov_y_deg = fov_y_deg;
  const Eigen::Vector3d center = box.IsEmpty() ? Eigen::Vector3d::Zero() : box.Center();
  const double radius = box.IsEmpty() ? 1.0 : std::max(0.5 * box.Extent().norm(), 1e-6);
  const Eigen::Vector3d dir = view_dir.norm() > 0 ? view_dir.normalized() : Eigen::Vector3d(0, 1, 0);
  // The bounding sphere fits the narrower field of view, with a 5 % margin.
  const double aspect = static_cast<double>(width) / height;
  const double half_fov = 0.5 * fov_y_deg * kPi / 180.0;
  const double half_narrow = aspect < 1 ? std::atan(std::tan(half_fov) * aspect) : half_fov;
  const double distance = 1.05 * radius / std::sin(half_narrow);
  camera.target = center;
  camera.eye = center - dir * distance;
  camera.up = std::abs(dir.dot(Eigen::Vector3d::UnitZ())) > 0.999 ? Eigen::Vector3d::UnitY()
                                                                   : Eigen::Vector3d::UnitZ();
  camera.ortho_height = 2.1 * radius / std::min(1.0, aspect);
  camera.near = std::max(1e-6, 1e-4 * distance);
  return camera;
}

double OrthographicDepthOffset(const Camera::Projector& p, const Box3d& bounds) {
  if (p.perspective || bounds.IsEmpty()) return 0.0;
  double zmin = 1e300;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d x(corner & 1 ? bounds.max[0] : bounds.min[0], corner & 2 ? bounds.max[1] : bounds.min[1],
                            corner & 4 ? bounds.max[2] : bounds.min[2]);
    zmin = std::min(zmin, (p.rotation * (x - p.eye)).z());
  }
  return std::max(0.0, 1.0 - zmin);
}

}  // namespace candi::render

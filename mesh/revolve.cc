#include "mesh/revolve.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/check.h"
#include "core/text_format.h"

namespace candi::mesh {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Throws when a side crosses to the other side of the axis (a revolved surface would pass
// through itself).
void CheckRadii(const Profile& profile, double axis, double eps) {
  for (const auto* side : {&profile.left, &profile.right}) {
    const bool left = side == &profile.left;
    for (const Eigen::Vector2d& p : *side) {
      const double r = left ? axis - p.x() : p.x() - axis;
      if (r < -eps) {
        FailSection(profile.source,
                    std::string("the ") + (left ? "left" : "right") +
                        " side crosses the axis x = " + FormatDouble(axis + profile.origin.x()) +
                        " at height " + FormatDouble(p.y() + profile.origin.y()) +
                        " m; choose another axis (--axis-x)");
      }
    }
  }
}

}  // namespace

std::string RevolveModeName(RevolveMode mode) {
  switch (mode) {
    case RevolveMode::kAuto:
      return "auto";
    case RevolveMode::kBlend:
      return "blend";
    case RevolveMode::kSweep:
      return "sweep";
  }
  return "?";
}

RevolveMode ParseRevolveMode(const std::string& name) {
  for (RevolveMode m : {RevolveMode::kAuto, RevolveMode::kBlend, RevolveMode::kSweep}) {
    if (RevolveModeName(m) == name) return m;
  }
  throw std::invalid_argument("revolve mode '" + name + "': must be auto, blend or sweep");
}

void RevolveOptions::Check() const {
  CANDI_CHECK_OPTION_IN(angular_steps, 2, 1000000);
  CANDI_CHECK_OPTION(!std::isinf(axis_x), axis_x, "finite (or NaN for the reference point)");
  CANDI_CHECK_OPTION_IN(symmetry_tolerance, 0, 1);
}

double ProfileAsymmetry(const Profile& profile, double axis_local_x) {
  CANDI_CHECK_EQ(profile.left.size(), profile.right.size());
  double worst = 0;
  for (size_t i = 0; i < profile.left.size(); ++i) {
    const Eigen::Vector2d& a = profile.left[i];
    const Eigen::Vector2d& b = profile.right[i];
    const double dr = std::abs((axis_local_x - a.x()) - (b.x() - axis_local_x));
    worst = std::max({worst, dr, std::abs(a.y() - b.y())});
  }
  return profile.extent > 0 ? worst / profile.extent : worst;
}

SurfaceGrid RevolveProfile(const RevolveOptions& options, const Profile& profile) {
  options.Check();
  const int n = static_cast<int>(profile.left.size()), m = options.angular_steps;
  CANDI_CHECK(n >= 2 && profile.right.size() == profile.left.size())
      << "RevolveProfile: sides of " << profile.left.size() << " and " << profile.right.size();
  const double axis =
      std::isnan(options.axis_x) ? profile.reference.x() : options.axis_x - profile.origin.x();
  const double eps = 1e-12 * std::max(profile.extent, 1.0);
  CheckRadii(profile, axis, eps);
  SurfaceGrid grid;
  grid.rings = n;
  grid.columns = 2 * m;
  grid.asymmetry = ProfileAsymmetry(profile, axis);
  grid.mode = options.mode != RevolveMode::kAuto             ? options.mode
              : grid.asymmetry <= options.symmetry_tolerance ? RevolveMode::kSweep
                                                             : RevolveMode::kBlend;
  grid.frame.origin = Eigen::Vector3d(profile.origin.x(), 0, profile.origin.y());
  grid.axis_point = Eigen::Vector3d(axis, 0, profile.reference.y());
  std::vector<double> cosines(static_cast<size_t>(m) + 1), sines(cosines.size());
  for (int j = 0; j <= m; ++j) {
    cosines[j] = std::cos(kPi * j / m);
    sines[j] = std::sin(kPi * j / m);
  }
  sines[0] = sines[m] = 0;  // sin(pi) is 1.2e-16 in double
  grid.positions.resize(static_cast<size_t>(n) * grid.columns);
  const bool sweep = grid.mode == RevolveMode::kSweep;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d& a = profile.left[i];
    const Eigen::Vector2d& b = profile.right[i];
    double rl = axis - a.x(), rr = b.x() - axis, yl = a.y(), yr = b.y();
    if (sweep) rl = rr = (rl + rr) / 2, yl = yr = (yl + yr) / 2;
    Eigen::Vector3d* ring = &grid.positions[static_cast<size_t>(i) * grid.columns];
    for (int j = 0; j <= m; ++j) {
      const double t = static_cast<double>(j) / m;
      const double r = (1 - t) * rl + t * rr, h = (1 - t) * yl + t * yr;
      ring[j] = Eigen::Vector3d(axis - r * cosines[j], r * sines[j], h);
    }
    if (!sweep) {  // the drawing itself at theta = 0 and pi, bit for bit
      ring[0] = Eigen::Vector3d(a.x(), 0, a.y());
      ring[m] = Eigen::Vector3d(b.x(), 0, b.y());
    }
    for (int j = m + 1; j < 2 * m; ++j) {
      ring[j] = ring[2 * m - j];
      ring[j].y() = -ring[j].y();
    }
  }
  auto on_axis = [&](int i) {
    return std::abs(axis - profile.left[i].x()) <= eps &&
           std::abs(profile.right[i].x() - axis) <= eps &&
           std::abs(profile.left[i].y() - profile.right[i].y()) <= eps;
  };
  grid.apex_top = on_axis(0);
  grid.apex_bottom = on_axis(n - 1);
  return grid;
}

}  // namespace candi::mesh

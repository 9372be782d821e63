// LocalFrame: the scene's origin shift.
//
// Survey coordinates reach 1e6-1e7 m; float keeps only ~0.1-1 m there. candi stores positions as
// double in a local frame whose origin is chosen once per scene: world = local + origin.
// Everything that runs in float (rendering, PCL, the network) works in local coordinates.
// With an integer origin the subtraction world - origin and the sum local + origin are exact in
// double for every |world - origin| <= |world|, so a round trip through the shift loses nothing.
#pragma once

#include <Eigen/Core>
#include <string>

namespace candi {

struct Box3d;

struct LocalFrame {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // world coordinates of the local origin, m

  bool IsIdentity() const { return origin.isZero(0.0); }
  Eigen::Vector3d ToWorld(const Eigen::Vector3d& x_in_local) const { return x_in_local + origin; }
  Eigen::Vector3d ToLocal(const Eigen::Vector3d& x_in_world) const { return x_in_world - origin; }

  // The automatic shift for data spanning `world_box`: zero when every coordinate is below
  // kAutoShiftThreshold in magnitude (float keeps sub-millimetre detail there), otherwise the box
  // centre rounded to a multiple of 100 m (an integer, so shifting is exact).
  static LocalFrame Auto(const Box3d& world_box);
  static constexpr double kAutoShiftThreshold = 1.0e4;  // m

  std::string ToString() const;  // "x,y,z" with full precision
  bool operator==(const LocalFrame& other) const { return origin == other.origin; }
  bool operator!=(const LocalFrame& other) const { return !(*this == other); }
};

// Parses "x,y,z" (three finite numbers). Throws std::invalid_argument naming the text.
LocalFrame ParseShift(const std::string& text);

}  // namespace candi

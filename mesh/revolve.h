// Rotational blending and sweep of a profile around a vertical axis (ALGORITHMS.md §2, steps 2-3).
//
// Left point A_i and right point B_i (matched by index) have radii rl = a - x_A, rr = x_B - a from
// the axis x = a and heights y_A, y_B. For theta in [0, pi], t = theta / pi:
//     r = (1 - t) rl + t rr,   h = (1 - t) y_A + t y_B,
//     position = (a - r cos theta,  r sin theta,  h)          (world axes: x, y, z up)
// and the other half-turn mirrors it (y -> -y). theta = 0 gives A and theta = pi gives B: the
// drawing's plane is world y = 0 and both sides are reproduced exactly there (the grid columns at
// theta = 0 and pi are set to the profile points themselves, not recomputed through cos/sin).
// This is the intent of the paper's Eq. 1, whose printed matrix is garbled.
// Sweep (a surface of revolution) uses the mean side, r = (rl + rr) / 2, h = (y_A + y_B) / 2,
// at every theta: exact for a symmetric layer, within the asymmetry otherwise.
// kAuto sweeps when the sides mirror each other within symmetry_tolerance x extent
// (max over i of |rl_i - rr_i| and |y_A,i - y_B,i|), and blends otherwise; the grid says which.
//
// Frame: the grid is local; world = local + frame.origin with world x = drawing x, world z =
// drawing y, world y = depth (the profile's origin becomes (origin.x, 0, origin.y)).
// Failures: a side crossing the axis (a negative radius beyond the tolerance) is InputError
// naming the file, layer and height. Thread-safe (pure function).
#pragma once

#include <Eigen/Core>
#include <limits>
#include <string>
#include <vector>

#include "core/local_frame.h"
#include "mesh/profile.h"

namespace candi::mesh {

enum class RevolveMode { kAuto, kBlend, kSweep };
std::string RevolveModeName(RevolveMode mode);          // "auto", "blend", "sweep"
RevolveMode ParseRevolveMode(const std::string& name);  // std::invalid_argument naming the text

struct RevolveOptions {
  RevolveMode mode = RevolveMode::kAuto;
  int angular_steps = 90;  // M, steps per half-turn (theta from 0 to pi), [2, 1e6]
  // Drawing x of the vertical axis, m; NaN = the vertical through the reference point.
  double axis_x = std::numeric_limits<double>::quiet_NaN();
  double symmetry_tolerance = 1e-3;  // relative to the section's extent, [0, 1]
  void Check() const;                // throws std::invalid_argument naming the field
};

struct SurfaceGrid {
  int rings = 0;    // N: profile samples per side; ring 0 holds the reference points
  int columns = 0;  // 2M: column j at theta = pi j / M; j > M mirrors column 2M - j
  std::vector<Eigen::Vector3d> positions;  // rings x columns, ring-major, local frame, m
  LocalFrame frame;
  Eigen::Vector3d axis_point = Eigen::Vector3d::Zero();  // local point on the (vertical) axis
  bool apex_top = false;                                 // ring 0 lies on the axis (one point)
  bool apex_bottom = false;                              // ring N-1 lies on the axis (one point)
  RevolveMode mode = RevolveMode::kBlend;                // the mode used: kBlend or kSweep
  double asymmetry = 0;  // max difference between the mirrored sides / extent

  const Eigen::Vector3d& At(int ring, int column) const {
    return positions[static_cast<size_t>(ring) * static_cast<size_t>(columns) +
                     static_cast<size_t>(column)];
  }
};

SurfaceGrid RevolveProfile(const RevolveOptions& options, const Profile& profile);

// max_i max(|rl_i - rr_i|, |y_A,i - y_B,i|) / extent for the axis at local x = axis_local_x.
double ProfileAsymmetry(const Profile& profile, double axis_local_x);

}  // namespace candi::mesh

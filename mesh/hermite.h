// Shape-preserving piecewise cubic Hermite interpolation (Fritsch-Carlson; the tangents of
// Fritsch & Butland 1984 as in PCHIP) and arc-length resampling of a polyline with it.
//
// Between two data points the interpolant never leaves the range of their values and keeps the
// data's monotonicity: no overshoot at corners, a flat run stays exactly flat (so a vertical
// segment of a polyline stays vertical when x(s) and y(s) are interpolated separately), and
// uneven spacing is handled by the weighted harmonic mean of the neighbouring slopes.
// Thread-safe (pure functions). Bad arguments (fewer than 2 points, t not strictly increasing,
// non-finite values) are misuse: CANDI_CHECK.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace candi::mesh {

struct MonotoneCubic {
  std::vector<double> t;      // knots, strictly increasing
  std::vector<double> value;  // data at the knots
  std::vector<double> slope;  // Hermite tangents d value / d t at the knots
  // The interpolant at x; x is clamped to [t.front(), t.back()]; exact at the knots.
  double Evaluate(double x) const;
};

MonotoneCubic FitMonotoneCubic(const std::vector<double>& t, const std::vector<double>& value);

// `count` (>= 2) points along the polyline through `vertices` (>= 2, consecutive vertices
// distinct): x(s) and y(s) are monotone cubics over the cumulative chord length s, sampled at
// equal steps of s from 0 to the total length. The first and last points equal the first and
// last vertices exactly.
std::vector<Eigen::Vector2d> ResampleByArcLength(const std::vector<Eigen::Vector2d>& vertices,
                                                 int count);

}  // namespace candi::mesh

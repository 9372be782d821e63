// Plane-cube cross-sections: the area behind the voxel density estimate.
//
// A plane with unit normal n cuts the unit cube [0,1]^3 at offset t (points x with n·x = t) in a
// polygon of area A(t). Over a grid of cells, a point of a uniformly sampled plane lies in a cell
// whose section has area A with probability proportional to A (the size-biased law), so the
// expected number of *other* points in a point's cell of side h is rho * h^2 * G(n), with
//
//     G(n) = ∫ A(t)^2 dt / ∫ A(t) dt = ∫ A(t)^2 dt        (∫ A dt = the cube's volume, 1).
//
// G = 1 for an axis-aligned plane, 2√2/3 ≈ 0.943 at 45° about one axis, 0.953 for n ∝ (1,1,1),
// and its minimum ≈ 0.932 near n ∝ (2,1,0): dividing a cell count by h^2 alone underestimates the
// density of a tilted surface by up to 7 %. Worse, G is an average over offsets: a plane whose
// normal has rational ratios (a wall at 45° to the grid) meets the cells at a few offsets only,
// and the mean section then depends on where the plane lies (from 0.75 to 1.5 times G at 45°).
// So the voxel estimate divides each cell's count by that cell's own section area A(t), from the
// plane fitted to its points; G documents the bias of count / h^2 (tests, benchmark).
// Pure functions; thread-safe.
#pragma once

#include <Eigen/Core>

namespace candi::sampling {

// A(t): area of {x in [0,1]^3 : n·x = t} for a unit normal n (0 outside the cube's span).
double PlaneInCubeArea(const Eigen::Vector3d& unit_normal, double offset);

// G(n), exactly: A(t) is piecewise quadratic between the projections of the cube's
// vertices, so 3-point Gauss-Legendre per piece integrates A^2 without error. `normal` need not
// be unit length; it must be finite and non-zero (CANDI_CHECK).
double SizeBiasedPlaneInCubeArea(const Eigen::Vector3d& normal);

}  // namespace candi::sampling

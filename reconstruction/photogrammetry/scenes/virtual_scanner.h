// A virtual terrestrial laser scanner: rays cast from a station over a regular azimuth x
// elevation grid onto a triangle mesh, keeping each ray's first hit (so walls occlude what lies
// behind them), for tests and benchmarks of scan registration.
//
// Frames: the scene's world coordinates are its vertices' (mesh.vertices.frame.ToWorld); the
// station is `world_from_scanner` (world coordinates, any magnitude: the rays are cast relative to
// the mesh's own double-precision origin, so survey coordinates keep sub-millimetre hits). The
// scanner's frame has x at azimuth 0, elevation 0; z up (elevation +90 degrees); azimuth turns
// from x towards y. The points returned are in the scanner's frame (frame origin zero): a
// registration has to recover `world_from_scanner`.
//
// Order: column by column (azimuth 0 first, as a scanner head turns), each column from the lowest
// elevation up; rays without a hit (or beyond max_range, or nearer than min_range) give no point.
// Noise: each kept range gets range_noise * N(0, 1) along its ray, N drawn from the ray's own
// counter-based hash of (seed, ray index) (core/rng.h): the same seed gives the same bytes
// whatever the thread count. The columns are cast in parallel (candi::ParallelFor).
// Failure: bad options throw std::invalid_argument; a mesh with a face index out of range, a
// non-finite vertex or a non-finite pose throws InputError. An empty mesh gives an empty cloud.
#pragma once

#include <cstdint>

#include "core/point_cloud.h"
#include "core/transform.h"
#include "core/tri_mesh.h"

namespace candi::photogrammetry {

struct VirtualScannerOptions {
  double azimuth_step_deg = 0.2;    // degrees between columns, (0, 90]; 360 deg are covered
  double elevation_step_deg = 0.2;  // degrees between rays of a column, (0, 90]
  double min_elevation_deg = -60;   // degrees, [-90, 90]: the lowest ray of a column
  double max_elevation_deg = 90;    // degrees, [min_elevation_deg, 90]: the highest ray
  double min_range = 0.5;           // m, >= 0: nearer hits are dropped (the scanner's blind zone)
  double max_range = 100;           // m, > min_range: farther hits are dropped
  double range_noise = 0.002;       // m, >= 0: Gaussian sigma of the range, along the ray
  uint64_t seed = 1;                // noise seed
  void Check() const;  // throws std::invalid_argument("VirtualScannerOptions::field = ...")
};

// The number of rays per column and of columns the options give (the grid ScanMesh casts).
int ScannerRows(const VirtualScannerOptions& options);
int ScannerColumns(const VirtualScannerOptions& options);

// One scan of `scene` from `world_from_scanner`; points in the scanner's frame (metres), with a
// float scalar field "range" (m, the noisy range) and a float field "ray" (the ray's index
// column * rows + row, exact below 2^24 rays). Thread-safe (reentrant).
PointCloud ScanMesh(const VirtualScannerOptions& options, const TriMesh& scene,
                    const Rigid3& world_from_scanner);

}  // namespace candi::photogrammetry

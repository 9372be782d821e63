// Points on a triangle mesh (ALGORITHMS.md §2, step 4).
//
// kArea: i.i.d. uniform points over the surface, an exact count (or round(density x area)):
// sample k picks triangle t with probability area_t / area (Walker's alias table, O(1) per
// point) and a uniform point in it (sqrt(r1) barycentric). Draw k's triangle comes from
// HashIndex(seed, k) and output slot j's point in its triangle from HashIndex(seed, j), so the
// output is the same for any thread count, and counts in equal-area patches are multinomial: the
// density, and so SPBR's opacity, is even. Points come out grouped by triangle (in triangle
// order), which keeps the placement cache-friendly.
// kPerTriangle: the paper's method, a fixed number of uniform points in every triangle; only
// uniform when all triangles have equal area (kept for comparison).
// Positions are in the mesh's local frame (the cloud keeps mesh.vertices.frame). With `normals`
// each point carries its triangle's unit normal (zero for a degenerate triangle); with `colour`
// and `layer` set, every point gets that colour and layer id.
// Failures: bad options are std::invalid_argument (Check); a mesh of zero area asked for points
// is InputError. Thread-safe (reentrant); `threads` limits the TBB workers used.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "core/point_cloud.h"
#include "core/tri_mesh.h"

namespace candi::sampling {

enum class SurfaceSamplingMode { kArea, kPerTriangle };

struct SurfaceSampleOptions {
  SurfaceSamplingMode mode = SurfaceSamplingMode::kArea;
  uint64_t count = 0;    // kArea: exact number of points; exactly one of count and density > 0
  double density = 0;    // kArea: points per m^2, >= 0 (count = round(density x area))
  int per_triangle = 0;  // kPerTriangle: points in each triangle, >= 1
  uint64_t seed = 1;     // seeds every random choice
  int threads = 0;       // worker threads, >= 0; 0 = all available
  bool normals = true;   // store each point's triangle normal
  std::optional<Rgb8> colour;  // colour of every point (none: no colour attribute)
  int layer = -1;              // layer id of every point, [0, 65535]; -1 = no layer attribute
  void Check() const;          // throws std::invalid_argument("SurfaceSampleOptions::field = ...")
};

PointCloud SampleSurface(const SurfaceSampleOptions& options, const TriMesh& mesh);

// The mesh's area, m^2 (sum of triangle areas).
double MeshArea(const TriMesh& mesh);

// Splits `total` into integer parts proportional to `weights` (>= 0, not all 0) summing exactly
// to total (largest remainder; ties to the lower index).
std::vector<uint64_t> SplitCount(uint64_t total, const std::vector<double>& weights);

}  // namespace candi::sampling

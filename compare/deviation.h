// Deviation of a compared cloud from a reference: how far each compared point lies from a
// reference cloud or mesh, as CloudCompare's distance tools (C2C, C2M, M3C2) and MeshLab's
// Hausdorff filter measure it.
//
//   C2C   the distance to the nearest reference point (unsigned), optionally to a local model of
//         the reference (a least-squares plane or quadric over the k reference points nearest to
//         the compared point); the model distance is used where it is smaller than the nearest
//         point's, as CloudCompare does (a model can only bring the surface closer).
//   C2M   the signed distance to a triangle mesh (CGAL's AABB tree), positive on the side the
//         triangles face (counter-clockwise seen from outside); the sign at an edge or a vertex
//         comes from its angle-weighted pseudo-normal (Baerentzen & Aanaes 2005), so a point
//         outside a convex corner is never called inside.
//   M3C2  Lague, Brodu & Leroux (2013): at each compared point (the core points), a normal by PCA
//         of the reference points within D/2, then both clouds' points in a cylinder of diameter
//         d along that normal (half-length max_depth) projected onto it; the distance is the
//         difference of the mean positions (compared minus reference, along the normal), and
//         LoD95 = 1.96 * (sqrt(s1^2/n1 + s2^2/n2) + registration_error) from each side's
//         standard deviation s and count n. |distance| > LoD95 flags a significant change.
//
// Every method gives one value per compared point, in the compared cloud's input order. Where a
// value is undefined (M3C2: too few points on a side or no normal; C2C with a model: the model
// falls back to the nearest point and is counted) it is NaN and counted, never a silent zero.
// Coordinates: both clouds are re-expressed about one common double-precision origin, so survey
// coordinates of 10^6 m keep micrometres; all arithmetic is in double. Results are the same
// bytes for any thread count (each point is computed on its own).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "core/progress.h"
#include "core/tri_mesh.h"

namespace candi::compare {

enum class Method { kC2C, kC2M, kM3C2 };
std::string MethodName(Method method);              // "c2c", "c2m", "m3c2"
Method ParseMethod(const std::string& name);        // throws std::invalid_argument

enum class LocalModel { kNone, kPlane, kQuadric };
std::string LocalModelName(LocalModel model);       // "none", "plane", "quadric"
LocalModel ParseLocalModel(const std::string& name);  // throws std::invalid_argument

// Which way M3C2's normals point: towards +z (or -z, ...; horizontal normals then towards +x,
// +y), or away from the reference cloud's centroid ("out": closed or curved objects).
enum class NormalOrientation { kPlusX, kMinusX, kPlusY, kMinusY, kPlusZ, kMinusZ, kOutward };
std::string NormalOrientationName(NormalOrientation orientation);  // "+x", ..., "out"
NormalOrientation ParseNormalOrientation(const std::string& name);  // throws std::invalid_argument

struct C2cOptions {
  LocalModel local_model = LocalModel::kNone;
  int model_neighbours = 12;  // k reference points a model is fitted to, [3, 1000] (quadric >= 6)
  void Check() const;
};

struct C2mOptions {
  bool signed_distance = true;  // false: |distance|
  void Check() const;
};

struct M3c2Options {
  double normal_scale = 0;        // D, m, >= 0: normals from reference points within D/2; 0 = 2 d
  double projection_scale = 0;    // d, m, >= 0: the cylinder's diameter; 0 = ~30 points in it
  double max_depth = 0;           // m, >= 0: the cylinder's half-length; 0 = the normal scale D
  double registration_error = 0;  // m, >= 0: added to LoD95 (the paper's "reg")
  int min_points = 3;             // points a side needs for a distance, [2, 1000000]
  NormalOrientation orientation = NormalOrientation::kPlusZ;
  void Check() const;
};

struct DeviationOptions {
  Method method = Method::kC2C;
  C2cOptions c2c;
  C2mOptions c2m;
  M3c2Options m3c2;
  int threads = 0;  // worker threads, >= 0; 0 = all cores. Results do not depend on it.
  void Check() const;
};

struct DeviationResult {
  Method method = Method::kC2C;
  std::vector<double> distance;  // per compared point, m; NaN where undefined
  uint64_t undefined = 0;        // NaN values in `distance`
  // C2C with a local model: points whose neighbourhood gave no model (coincident or collinear
  // points), measured to the nearest point instead.
  uint64_t model_fallbacks = 0;
  // M3C2 only (empty otherwise), per compared point:
  std::vector<double> lod95;                 // m; NaN where the distance is undefined
  std::vector<uint8_t> significant;          // 1 where |distance| > lod95
  std::vector<Eigen::Vector3f> normals;      // the projection direction; NaN where none
  std::vector<uint32_t> reference_count, compared_count;  // points in the cylinder, each side
  std::vector<double> reference_std, compared_std;        // their spread along the normal, m
  uint64_t no_normal = 0;        // M3C2: reference neighbourhood within D/2 defines no plane
  uint64_t too_few_points = 0;   // M3C2: a side had fewer than min_points in the cylinder
  double normal_scale = 0, projection_scale = 0, max_depth = 0;  // M3C2: the scales used, m
  // Plain-language notes for the user (e.g. the clouds do not overlap at all).
  std::vector<std::string> warnings;
};

// The compared cloud against a reference cloud (C2C, M3C2). Throws InputError naming
// `reference_name` or `compared_name` for an empty cloud or a position that is not finite;
// std::invalid_argument for bad options or kC2M. `progress` receives points done out of total.
DeviationResult CompareToCloud(const DeviationOptions& options, const PointCloud& reference,
                               const PointCloud& compared, const std::string& reference_name,
                               const std::string& compared_name,
                               const ProgressCallback& progress = nullptr);

// The compared cloud against a triangle mesh (C2M). Throws InputError for a mesh without faces
// (or only degenerate ones), a face index out of range, a vertex or point that is not finite.
DeviationResult CompareToMesh(const DeviationOptions& options, const TriMesh& reference,
                              const PointCloud& compared, const std::string& reference_name,
                              const std::string& compared_name,
                              const ProgressCallback& progress = nullptr);

// M3C2's automatic scales for a reference cloud: the surface density from the median distance
// of up to 1000 evenly spread points to their 16th neighbour; d such that a cylinder of diameter d
// holds ~30 reference points on a surface, D = 2 d. Returns {D, d}. Throws InputError when fewer
// than 17 distinct points give no density.
std::pair<double, double> AutoM3c2Scales(const PointCloud& reference);

// The compared cloud with the result as scalar fields: "distance" (float), and for M3C2 also
// "lod95", "significant" (0/1), "n_reference", "n_compared", "std_reference", "std_compared",
// and the normals. Fields of those names already present are replaced.
PointCloud WithDeviationFields(const PointCloud& compared, const DeviationResult& result);

}  // namespace candi::compare

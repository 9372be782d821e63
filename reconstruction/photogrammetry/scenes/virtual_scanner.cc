// Ray casting through a bounding-volume hierarchy of the mesh's triangles (median split on the
// longest axis of the centroids, leaves of <= 4 triangles), nearest child first, and the
// Moeller-Trumbore ray-triangle test (J. Graphics Tools 2(1), 1997), all in double in the mesh's
// local frame.
#include "reconstruction/photogrammetry/scenes/virtual_scanner.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/check.h"
#include "core/parallel.h"
#include "core/rng.h"

namespace candi::photogrammetry {

namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kInf = std::numeric_limits<double>::infinity();

struct Triangle {
  Eigen::Vector3d a, e1, e2;  // vertex a and the edges b - a, c - a
};

struct Node {
  Eigen::Vector3d min, max;
  uint32_t first = 0;  // leaf: first triangle; inner: the right child (the left is this + 1)
  uint32_t count = 0;  // triangles in a leaf; 0 for an inner node
};

class Bvh {
 public:
  explicit Bvh(std::vector<Triangle> triangles);
  // Distance along `dir` (unit) to the first triangle hit at t in (t_min, t_max), else +inf.
  double Cast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min,
              double t_max) const;

 private:
  uint32_t Build(uint32_t first, uint32_t count);
  std::vector<Triangle> triangles_;
  std::vector<Eigen::Vector3d> centroids_;
  std::vector<Node> nodes_;
};

Bvh::Bvh(std::vector<Triangle> triangles) : triangles_(std::move(triangles)) {
  centroids_.reserve(triangles_.size());
  for (const Triangle& t : triangles_) centroids_.push_back(t.a + (t.e1 + t.e2) / 3.0);
  if (!triangles_.empty()) Build(0, static_cast<uint32_t>(triangles_.size()));
}

uint32_t Bvh::Build(uint32_t first, uint32_t count) {
  const uint32_t index = static_cast<uint32_t>(nodes_.size());
  nodes_.emplace_back();
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(kInf), hi = -lo, clo = lo, chi = -lo;
  for (uint32_t i = first; i < first + count; ++i) {
    const Triangle& t = triangles_[i];
    for (const Eigen::Vector3d& p :
         {t.a, Eigen::Vector3d(t.a + t.e1), Eigen::Vector3d(t.a + t.e2)}) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    clo = clo.cwiseMin(centroids_[i]);
    chi = chi.cwiseMax(centroids_[i]);
  }
  nodes_[index].min = lo;
  nodes_[index].max = hi;
  int axis = 0;
  (chi - clo).maxCoeff(&axis);
  if (count <= 4 || chi[axis] - clo[axis] <= 0) {
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  }
  // Median split: triangles (and their centroids) reordered together through an index.
  std::vector<uint32_t> order(count);
  for (uint32_t i = 0; i < count; ++i) order[i] = first + i;
  const uint32_t half = count / 2;
  std::nth_element(order.begin(), order.begin() + half, order.end(), [&](uint32_t x, uint32_t y) {
    const double cx = centroids_[x][axis], cy = centroids_[y][axis];
    return cx < cy || (cx == cy && x < y);
  });
  std::vector<Triangle> tri(count);
  std::vector<Eigen::Vector3d> cen(count);
  for (uint32_t i = 0; i < count; ++i) {
    tri[i] = triangles_[order[i]];
    cen[i] = centroids_[order[i]];
  }
  std::copy(tri.begin(), tri.end(), triangles_.begin() + first);
  std::copy(cen.begin(), cen.end(), centroids_.begin() + first);
  Build(first, half);
  const uint32_t right = Build(first + half, count - half);
  nodes_[index].first = right;
  return index;
}

// Entry distance of the ray into the box (slab test), or +inf when it misses within [0, t_max].
double EnterBox(const Node& n, const Eigen::Vector3d& o, const Eigen::Vector3d& inv, double t_max) {
  double t0 = 0, t1 = t_max;
  for (int k = 0; k < 3; ++k) {
    double a = (n.min[k] - o[k]) * inv[k], b = (n.max[k] - o[k]) * inv[k];
    if (a > b) std::swap(a, b);
    t0 = a > t0 ? a : t0;  // NaN (0 * inf on a slab's face) leaves the bound unchanged
    t1 = b < t1 ? b : t1;
  }
  return t0 <= t1 ? t0 : kInf;
}

double HitTriangle(const Triangle& t, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  const Eigen::Vector3d p = d.cross(t.e2);
  const double det = t.e1.dot(p);
  if (std::abs(det) < 1e-300) return kInf;  // parallel to the plane (or degenerate)
  const double inv = 1.0 / det;
  const Eigen::Vector3d s = o - t.a;
  const double u = s.dot(p) * inv;
  if (u < 0 || u > 1) return kInf;
  const Eigen::Vector3d q = s.cross(t.e1);
  const double v = d.dot(q) * inv;
  if (v < 0 || u + v > 1) return kInf;
  return t.e2.dot(q) * inv;
}

double Bvh::Cast(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min,
                 double t_max) const {
  if (nodes_.empty()) return kInf;
  const Eigen::Vector3d inv = d.cwiseInverse();
  double best = t_max;
  bool hit = false;
  std::array<uint32_t, 64> stack;
  int top = 0;
  if (EnterBox(nodes_[0], o, inv, best) == kInf) return kInf;
  stack[top++] = 0;
  while (top > 0) {
    const Node& n = nodes_[stack[--top]];
    if (EnterBox(n, o, inv, best) == kInf) continue;
    if (n.count > 0) {
      for (uint32_t i = n.first; i < n.first + n.count; ++i) {
        const double t = HitTriangle(triangles_[i], o, d);
        if (t > t_min && t < best) best = t, hit = true;
      }
      continue;
    }
    const uint32_t left = static_cast<uint32_t>(&n - nodes_.data()) + 1, right = n.first;
    const double tl = EnterBox(nodes_[left], o, inv, best),
                 tr = EnterBox(nodes_[right], o, inv, best);
    // Push the farther child first so the nearer is searched first (and shrinks `best`).
    if (tl <= tr) {
      if (tr != kInf) stack[top++] = right;
      if (tl != kInf) stack[top++] = left;
    } else {
      if (tl != kInf) stack[top++] = left;
      if (tr != kInf) stack[top++] = right;
    }
  }
  return hit ? best : kInf;
}

std::vector<Triangle> MeshTriangles(const TriMesh& scene) {
  const std::vector<Eigen::Vector3d>& v = scene.vertices.positions;
  for (size_t i = 0; i < v.size(); ++i) {
    if (!v[i].allFinite()) {
      throw InputError("scene mesh", "vertex " + std::to_string(i), "position is not finite");
    }
  }
  std::vector<Triangle> out;
  out.reserve(scene.faces.size());
  for (size_t f = 0; f < scene.faces.size(); ++f) {
    for (uint32_t k : scene.faces[f]) {
      if (k >= v.size()) {
        throw InputError(
            "scene mesh", "face " + std::to_string(f),
            "vertex index " + std::to_string(k) + " >= " + std::to_string(v.size()) + " vertices");
      }
    }
    const auto& idx = scene.faces[f];
    out.push_back({v[idx[0]], v[idx[1]] - v[idx[0]], v[idx[2]] - v[idx[0]]});
  }
  return out;
}

// A standard normal from the ray's two hashes (Box-Muller).
double RayNormal(uint64_t seed, uint64_t ray) {
  const double u1 = ToUnit(HashIndex(seed, ray, 1)), u2 = ToUnit(HashIndex(seed, ray, 2));
  return std::sqrt(-2.0 * std::log(1.0 - u1)) * std::cos(2.0 * M_PI * u2);
}

}  // namespace

void VirtualScannerOptions::Check() const {
  CANDI_CHECK_OPTION(azimuth_step_deg > 0 && azimuth_step_deg <= 90, azimuth_step_deg,
                     "in (0, 90]");
  CANDI_CHECK_OPTION(elevation_step_deg > 0 && elevation_step_deg <= 90, elevation_step_deg,
                     "in (0, 90]");
  CANDI_CHECK_OPTION_IN(min_elevation_deg, -90, 90);
  CANDI_CHECK_OPTION(max_elevation_deg >= min_elevation_deg && max_elevation_deg <= 90,
                     max_elevation_deg, "in [min_elevation_deg, 90]");
  CANDI_CHECK_OPTION(std::isfinite(min_range) && min_range >= 0, min_range, "finite and >= 0");
  CANDI_CHECK_OPTION(std::isfinite(max_range) && max_range > min_range, max_range,
                     "finite and > min_range");
  CANDI_CHECK_OPTION(std::isfinite(range_noise) && range_noise >= 0, range_noise,
                     "finite and >= 0");
}

int ScannerRows(const VirtualScannerOptions& o) {
  return static_cast<int>(std::floor(
             (o.max_elevation_deg - o.min_elevation_deg) / o.elevation_step_deg + 1e-9)) +
         1;
}

int ScannerColumns(const VirtualScannerOptions& o) {
  return std::max(1, static_cast<int>(std::lround(360.0 / o.azimuth_step_deg)));
}

PointCloud ScanMesh(const VirtualScannerOptions& options, const TriMesh& scene,
                    const Rigid3& world_from_scanner) {
  options.Check();
  if (!world_from_scanner.translation.allFinite() ||
      !world_from_scanner.rotation.coeffs().allFinite()) {
    throw InputError("scanner pose", "", "world_from_scanner is not finite");
  }
  const Bvh bvh(MeshTriangles(scene));
  const int rows = ScannerRows(options), cols = ScannerColumns(options);
  const double az_step = 360.0 / cols;
  const Eigen::Matrix3d r = world_from_scanner.rotation.toRotationMatrix();
  const Eigen::Vector3d station = world_from_scanner.translation - scene.vertices.frame.origin;
  std::vector<std::vector<std::pair<uint64_t, double>>> hits(cols);  // (ray, range) per column
  ParallelFor(0, cols, [&](int c) {
    const double az = c * az_step * kDeg;
    for (int k = 0; k < rows; ++k) {
      const double el = (options.min_elevation_deg + k * options.elevation_step_deg) * kDeg;
      const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                              std::sin(el));
      const double t = bvh.Cast(station, r * d, options.min_range, options.max_range);
      if (t == kInf) continue;
      const uint64_t ray = static_cast<uint64_t>(c) * rows + k;
      const double noise =
          options.range_noise > 0 ? options.range_noise * RayNormal(options.seed, ray) : 0.0;
      hits[c].emplace_back(ray, t + noise);
    }
  });
  PointCloud cloud;
  PointSchema schema;
  schema.scalars = {{"range", ScalarType::kFloat32}, {"ray", ScalarType::kFloat64}};
  cloud.SetSchema(schema);
  for (const auto& column : hits) {
    for (const auto& [ray, range] : column) {
      const double az = static_cast<double>(ray / rows) * az_step * kDeg;
      const double el = (options.min_elevation_deg +
                         static_cast<double>(ray % rows) * options.elevation_step_deg) *
                        kDeg;
      const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                              std::sin(el));
      cloud.positions.push_back(range * d);
      cloud.scalars[0].f32.push_back(static_cast<float>(range));
      cloud.scalars[1].f64.push_back(static_cast<double>(ray));
    }
  }
  return cloud;
}

}  // namespace candi::photogrammetry

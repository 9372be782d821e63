// Test helper (header-only): a courtyard scene as a triangle mesh, made in code, for the virtual
// scanner and scan-registration tests, a ring of scanner stations inside it and the tests' scanner.
//
// The courtyard (local metres): floor z = 0 over [-1, 41] x [-1, 31]; outer walls 0.4 m thick and
// 4 m high along the edges of [0, 40] x [0, 30]; a central building 8 x 6 x 7 m at
// [16, 24] x [12, 18]; six pillars (0.6 x 0.6 m, 3 m high), a flight of three steps and a ramp
// (a tilted slab), so every scan sees planes in all three directions (all six degrees of freedom
// constrained) and the building hides parts of the yard from each station. Stored in the mesh's
// frame `origin` (world = local + origin).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/transform.h"
#include "core/tri_mesh.h"
#include "reconstruction/photogrammetry/scenes/virtual_scanner.h"

namespace candi::testing {

// Adds the quad a, b, c, d (counter-clockwise seen from the side it faces) as two triangles.
inline void AddQuad(TriMesh* mesh, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                    const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  const uint32_t n = static_cast<uint32_t>(mesh->vertices.positions.size());
  for (const Eigen::Vector3d* p : {&a, &b, &c, &d}) mesh->vertices.positions.push_back(*p);
  mesh->faces.push_back({n, n + 1, n + 2});
  mesh->faces.push_back({n, n + 2, n + 3});
}

// An axis-aligned box [lo, hi] (local metres), its six faces facing outwards.
inline void AddBox(TriMesh* mesh, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  auto p = [&](int i) {
    return Eigen::Vector3d((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                           (i & 4) ? hi.z() : lo.z());
  };
  AddQuad(mesh, p(0), p(2), p(3), p(1));  // bottom (-z)
  AddQuad(mesh, p(4), p(5), p(7), p(6));  // top (+z)
  AddQuad(mesh, p(0), p(1), p(5), p(4));  // -y
  AddQuad(mesh, p(2), p(6), p(7), p(3));  // +y
  AddQuad(mesh, p(0), p(4), p(6), p(2));  // -x
  AddQuad(mesh, p(1), p(3), p(7), p(5));  // +x
}

inline TriMesh CourtyardScene(const Eigen::Vector3d& origin = Eigen::Vector3d::Zero()) {
  using V = Eigen::Vector3d;
  TriMesh mesh;
  mesh.vertices.frame.origin = origin;
  AddQuad(&mesh, V(-1, -1, 0), V(41, -1, 0), V(41, 31, 0), V(-1, 31, 0));  // floor
  AddBox(&mesh, V(-0.4, -0.4, 0), V(40.4, 0, 4));                          // south wall
  AddBox(&mesh, V(-0.4, 30, 0), V(40.4, 30.4, 4));                         // north wall
  AddBox(&mesh, V(-0.4, 0, 0), V(0, 30, 4));                               // west wall
  AddBox(&mesh, V(40, 0, 0), V(40.4, 30, 4));                              // east wall
  AddBox(&mesh, V(16, 12, 0), V(24, 18, 7));                               // building
  for (const auto& c :
       std::vector<std::array<double, 2>>{{6, 6}, {33, 5}, {35, 24}, {7, 23}, {13, 27}, {30, 7}}) {
    AddBox(&mesh, V(c[0] - 0.3, c[1] - 0.3, 0), V(c[0] + 0.3, c[1] + 0.3, 3));  // pillars
  }
  for (int s = 0; s < 3; ++s) {  // steps against the west wall
    AddBox(&mesh, V(0, 10 + 0.4 * s, 0), V(3 - 0.8 * s, 14 - 0.4 * s, 0.18 * (s + 1)));
  }
  AddQuad(&mesh, V(30, 20, 0), V(34, 20, 0), V(34, 23, 1.2), V(30, 23, 1.2));  // ramp
  return mesh;
}

// `count` stations on a circle of `radius` m around the building's centre, 1.6 m above the floor,
// each turned by a different heading (so no two scanner frames are aligned); local metres plus
// `origin`, i.e. world coordinates.
inline std::vector<Rigid3> CourtyardStations(
    int count, double radius = 10.5, const Eigen::Vector3d& origin = Eigen::Vector3d::Zero()) {
  std::vector<Rigid3> out;
  for (int i = 0; i < count; ++i) {
    const double a = 2.0 * M_PI * i / count;
    const Eigen::Vector3d c(20 + radius * std::cos(a), 15 + 0.8 * radius * std::sin(a), 1.6);
    const Eigen::Quaterniond q(Eigen::AngleAxisd(0.7 * i + 0.3, Eigen::Vector3d::UnitZ()));
    out.emplace_back(q, c + origin);
  }
  return out;
}

// The scanner of the registration tests: 0.4 degree steps over elevations [-60, 60] (about
// 1.7e5 points a station in the courtyard), 1 mm range noise, seeded.
inline photogrammetry::VirtualScannerOptions CourtyardScanner(uint64_t seed) {
  photogrammetry::VirtualScannerOptions o;
  o.azimuth_step_deg = o.elevation_step_deg = 0.4;
  o.min_elevation_deg = -60;
  o.max_elevation_deg = 60;
  o.max_range = 40;
  o.range_noise = 0.001;
  o.seed = seed;
  return o;
}

}  // namespace candi::testing

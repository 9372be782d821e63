// TriMesh: vertices (a PointCloud, so they carry colours, normals, fields and a frame) and
// triangles as indices into them (counter-clockwise seen from outside).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/point_cloud.h"

namespace candi {

struct TriMesh {
  PointCloud vertices;
  std::vector<std::array<uint32_t, 3>> faces;
};

}  // namespace candi

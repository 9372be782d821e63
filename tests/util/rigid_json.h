// Test helper (header-only): a rigid transform as the rows of the 4x4 that registration's JSON
// holds (candi register --transform-out, registration.json), and back.
#pragma once

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "core/transform.h"

namespace candi::testing {

inline nlohmann::json RigidJson(const Rigid3& t) {
  const Eigen::Matrix4d m = t.ToMatrix();
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < 4; ++i) rows.push_back({m(i, 0), m(i, 1), m(i, 2), m(i, 3)});
  return rows;
}

inline Rigid3 RigidFromJson(const nlohmann::json& m) {
  Eigen::Matrix3d r;
  Eigen::Vector3d t;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) r(i, j) = m[i][j].get<double>();
    t[i] = m[i][3].get<double>();
  }
  return Rigid3(Eigen::Quaterniond(r), t);
}

}  // namespace candi::testing

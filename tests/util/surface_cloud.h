// Test helper (header-only): points sampled from a known smooth surface, made in code with a
// seeded RNG, for registration and cleaning tests and benchmarks.
//
// The surface is the height field z = f(x, y) below (waves in x and y with different
// wavelengths plus a tilt), so point-to-plane ICP is constrained in all six degrees of freedom.
// Points are uniform in [x0, x1] x [y0, y1]; positions are stored in the frame `origin` (world =
// local + origin); each point carries the exact unit normal, an 8-bit colour, a layer and a
// double scalar field "id" = its index (to follow points through a filter).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

#include "core/point_cloud.h"
#include "core/rng.h"

namespace candi::testing {

struct SurfaceCloudSpec {
  size_t count = 20000;
  uint64_t seed = 1;
  double x0 = 0, x1 = 10, y0 = 0, y1 = 10;  // local metres
  double noise = 0;                         // Gaussian sigma along z, m
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // the cloud's frame (world shift)
};

inline double SurfaceHeight(double x, double y) {
  return 0.30 * std::sin(0.9 * x) * std::cos(0.7 * y) + 0.15 * std::sin(1.7 * y + 0.3) +
         0.05 * x;
}

inline Eigen::Vector3d SurfaceNormal(double x, double y) {
  const double fx = 0.27 * std::cos(0.9 * x) * std::cos(0.7 * y) + 0.05;
  const double fy = -0.21 * std::sin(0.9 * x) * std::sin(0.7 * y) + 0.255 * std::cos(1.7 * y + 0.3);
  return Eigen::Vector3d(-fx, -fy, 1.0).normalized();
}

inline PointCloud SurfaceCloud(const SurfaceCloudSpec& spec) {
  PointCloud cloud;
  PointSchema schema;
  schema.colors = schema.normals = schema.layers = true;
  schema.scalars.push_back({"id", ScalarType::kFloat64});
  cloud.SetSchema(schema);
  cloud.frame.origin = spec.origin;
  cloud.Resize(spec.count);
  Rng rng(spec.seed);
  for (size_t i = 0; i < spec.count; ++i) {
    const double x = rng.Uniform(spec.x0, spec.x1), y = rng.Uniform(spec.y0, spec.y1);
    const double z = SurfaceHeight(x, y) + (spec.noise > 0 ? spec.noise * rng.Normal() : 0.0);
    cloud.positions[i] = Eigen::Vector3d(x, y, z);
    cloud.normals[i] = SurfaceNormal(x, y).cast<float>();
    cloud.colors[i] = Rgb8{static_cast<uint8_t>(i % 251),
                           static_cast<uint8_t>(static_cast<int64_t>(std::floor(x * 20)) & 255),
                           static_cast<uint8_t>(static_cast<int64_t>(std::floor(y * 20)) & 255)};
    cloud.layers[i] = static_cast<uint16_t>(i % 7);
    cloud.scalars[0].f64[i] = static_cast<double>(i);
  }
  return cloud;
}

}  // namespace candi::testing

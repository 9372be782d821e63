#include "render/synthetic_scene.h"

#include <cmath>

#include "core/rng.h"

namespace candi::render {

namespace {
constexpr double kPi = 3.14159265358979323846;

Rgb8 Shade(Rgb8 base, double f) {
  auto c = [f](uint8_t v) { return static_cast<uint8_t>(std::clamp(v * f, 0.0, 255.0)); };
  return {c(base.r), c(base.g), c(base.b)};
}
// n points with positions and colours (to be filled in).
PointCloud ColouredCloud(uint64_t n) {
  PointCloud c;
  c.schema.colors = true;
  c.SetSchema(c.schema);
  c.Resize(n);
  return c;
}
}  // namespace

PointCloud LayeredSheets(uint64_t n, int layers, uint64_t seed) {
  PointCloud c = ColouredCloud(n);
  Rng rng(seed);
  const Rgb8 palette[6] = {{230, 90, 60}, {60, 160, 230}, {240, 210, 70}, {90, 200, 110},
                           {200, 120, 220}, {220, 220, 220}};
  for (uint64_t i = 0; i < n; ++i) {
    const int k = static_cast<int>(i % layers);
    const double x = rng.Uniform(-50, 50), y = rng.Uniform(-50, 50);
    // Each sheet is shifted sideways so the image shows 1..layers overlaps.
    const double shift = 15.0 * (k - 0.5 * (layers - 1));
    c.positions[i] = Eigen::Vector3d(x + shift, y, 10.0 * k + 0.05 * x + 0.03 * y);
    c.colors[i] = Shade(palette[k % 6], 0.85 + 0.15 * rng.Uniform());
  }
  return c;
}

PointCloud UniformRectangle(uint64_t n, double sx, double sy, double z, Rgb8 color, uint64_t seed) {
  PointCloud c = ColouredCloud(n);
  Rng rng(seed);
  for (uint64_t i = 0; i < n; ++i) {
    c.positions[i] = Eigen::Vector3d(rng.Uniform(0, sx), rng.Uniform(0, sy), z);
    c.colors[i] = color;
  }
  return c;
}

PointCloud TerracedSolid(uint64_t n, uint64_t seed) {
  PointCloud c = ColouredCloud(n);
  Rng rng(seed);
  for (uint64_t i = 0; i < n; ++i) {
    const double pick = rng.Uniform();
    Eigen::Vector3d p;
    if (pick < 0.8) {  // six square terraces: walls and tops
      const int k = static_cast<int>(rng.Below(6));
      const double a = 56.0 - 5.5 * k, z0 = 3.0 * k, z1 = z0 + 3.0;
      const double t = rng.Uniform(-a, a);
      if (rng.Uniform() < 0.5) {
        const int side = static_cast<int>(rng.Below(4));
        const double z = rng.Uniform(z0, z1);
        p = side == 0 ? Eigen::Vector3d(t, -a, z) : side == 1 ? Eigen::Vector3d(a, t, z)
          : side == 2 ? Eigen::Vector3d(t, a, z) : Eigen::Vector3d(-a, t, z);
      } else {
        p = Eigen::Vector3d(t, rng.Uniform(-a, a), z1);
      }
    } else {  // the dome
      const double phi = rng.Uniform(0, 2 * kPi), cz = rng.Uniform();
      const double s = std::sqrt(1 - cz * cz);
      p = Eigen::Vector3d(12 * s * std::cos(phi), 12 * s * std::sin(phi), 18 + 14 * cz);
    }
    c.positions[i] = p;
    const double h = std::clamp(p.z() / 32.0, 0.0, 1.0);
    c.colors[i] = Shade(Rgb8{static_cast<uint8_t>(150 + 80 * h), 140, static_cast<uint8_t>(120 - 40 * h)},
                        0.8 + 0.2 * rng.Uniform());
  }
  return c;
}

Camera ObliqueView(const Box3d& bounds, int width, int height) {
  return FrameBox(bounds, width, height, Eigen::Vector3d(0.45, 0.7, -0.55));
}

}  // namespace candi::render

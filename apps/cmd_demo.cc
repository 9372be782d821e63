// candi demo: until the integrated Borobudur example exists, renders a built-in scene (a stepped
// temple of square and circular terraces with small stupas) with the best renderer candi has.
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "apps/commands.h"
#include "core/log.h"
#include "core/png_io.h"
#include "core/point_io.h"
#include "core/rng.h"
#include "render/camera.h"
#include "render/spbr.h"
#include "render/splat_cloud.h"

namespace candi::app {

namespace {

constexpr double kPi = 3.14159265358979323846;

Rgb8 Stone(Rng& rng, double shade) {
  const double g = std::clamp(shade * (0.85 + 0.15 * rng.Uniform()), 0.0, 1.0);
  return {static_cast<uint8_t>(150 * g + 40), static_cast<uint8_t>(140 * g + 35), static_cast<uint8_t>(120 * g + 30)};
}

void AddPoint(PointCloud* c, const Eigen::Vector3d& p, Rgb8 color) {
  c->positions.push_back(p);
  c->colors.push_back(color);
}

// A square terrace: four walls of half-size a between heights z0 and z1, and its top ring.
void SquareTerrace(double a, double inner, double z0, double z1, double density, Rng& rng, PointCloud* c) {
  const size_t wall = static_cast<size_t>(density * 8 * a * (z1 - z0));
  for (size_t i = 0; i < wall; ++i) {
    const double t = rng.Uniform(-a, a), z = rng.Uniform(z0, z1);
    const int side = static_cast<int>(rng.Below(4));
    const Eigen::Vector3d p = side == 0 ? Eigen::Vector3d(t, -a, z) : side == 1 ? Eigen::Vector3d(a, t, z)
                            : side == 2 ? Eigen::Vector3d(t, a, z) : Eigen::Vector3d(-a, t, z);
    AddPoint(c, p, Stone(rng, side % 2 == 0 ? 0.8 : 0.6));
  }
  const size_t top = static_cast<size_t>(density * 4 * (a * a - inner * inner));
  for (size_t i = 0; i < top; ++i) {
    const double x = rng.Uniform(-a, a), y = rng.Uniform(-a, a);
    if (std::max(std::abs(x), std::abs(y)) < inner) continue;
    AddPoint(c, Eigen::Vector3d(x, y, z1), Stone(rng, 1.0));
  }
}

// A dome (half ellipsoid) of radius r and height hgt standing at base.
void Dome(const Eigen::Vector3d& base, double r, double hgt, double density, Rng& rng, PointCloud* c) {
  const size_t n = static_cast<size_t>(density * 2 * kPi * r * std::max(r, hgt));
  for (size_t i = 0; i < n; ++i) {
    const double phi = rng.Uniform(0, 2 * kPi), cz = rng.Uniform(0, 1);
    const double s = std::sqrt(1 - cz * cz);
    AddPoint(c, base + Eigen::Vector3d(r * s * std::cos(phi), r * s * std::sin(phi), hgt * cz),
             Stone(rng, 0.6 + 0.4 * cz));
  }
}

PointCloud BuiltinScene(uint64_t seed) {
  PointCloud cloud;
  cloud.schema.colors = true;
  cloud.SetSchema(cloud.schema);
  Rng rng(seed);
  const double density = 60.0;  // points per m^2
  double z = 0;
  for (int k = 0; k < 6; ++k) {  // six square terraces
    const double a = 56.0 - 5.5 * k, h = k == 0 ? 4.0 : 3.0;
    SquareTerrace(a, 56.0 - 5.5 * (k + 1), z, z + h, density, rng, &cloud);
    z += h;
  }
  for (int k = 0; k < 3; ++k) {  // three circular terraces with rings of small stupas
    const double ring = 25.0 - 6.0 * k;
    const int stupas = k == 0 ? 32 : k == 1 ? 24 : 16;
    for (int s = 0; s < stupas; ++s) {
      const double phi = 2 * kPi * s / stupas;
      Dome(Eigen::Vector3d(ring * std::cos(phi), ring * std::sin(phi), z), 1.8, 3.2, density, rng, &cloud);
    }
    z += 1.5;
  }
  Dome(Eigen::Vector3d(0, 0, z), 8.0, 10.0, density, rng, &cloud);  // the central stupa
  cloud.CheckConsistent();
  return cloud;
}

}  // namespace

int RunDemo(const DemoArgs& args) {
  std::filesystem::create_directories(args.output_dir);
  LogInfo("candi demo: the integrated Borobudur example is not built yet; rendering the built-in "
          "scene (a stepped temple) with SPBR, candi's renderer, transparent and opaque");
  const PointCloud scene = BuiltinScene(args.seed);
  LogInfo("built-in scene: " + std::to_string(scene.size()) + " points");
  const std::string ply = args.output_dir + "/builtin_scene.ply";
  WritePointCloud(ply, scene);
  for (const int repeat_level : {1, 100}) {
    render::SplatCloudOptions build;
    build.repeat_level = repeat_level;
    build.seed = args.seed;
    const render::SplatCloud splats = render::BuildSplatCloud(build, {&scene});
    const render::Camera camera = render::FrameBox(splats.bounds, args.width, args.height,
                                                   Eigen::Vector3d(0.55, 0.75, -0.45));
    const render::SpbrResult result = render::RenderSpbr({}, camera, splats);
    const double gain = repeat_level > 1 ? render::AutoBrightnessGain(result) : 1.0;
    const Image8 image = render::ToImage8(render::AverageImage(result, Rgb8{0, 0, 0}, gain));
    const std::string png = args.output_dir + (repeat_level == 1 ? "/builtin_opaque.png" : "/builtin_spbr.png");
    WritePng(png, image, {{"Software", std::string("candi demo (SPBR)")},
                          {"candi:seed", std::to_string(args.seed)},
                          {"candi:repeat_level", std::to_string(repeat_level)},
                          {"candi:brightness_gain", std::to_string(gain)}});
    std::printf("wrote %s (%dx%d, SPBR L=%d, %.0f ms, gain %.2f)\n", png.c_str(), image.width(),
                image.height(), repeat_level, result.milliseconds, gain);
  }
  return kOk;
}

}  // namespace candi::app

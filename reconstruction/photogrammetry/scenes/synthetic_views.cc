#include "reconstruction/photogrammetry/scenes/synthetic_views.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>

#include "core/check.h"
#include "core/parallel.h"
#include "core/rng.h"
#include "io/image/png_io.h"

namespace candi::photogrammetry {

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Hit {
  double t = -1;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  int primitive = -1;
};

double SmoothStep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

// The carved surface's outward normal at (u, v): the face's normal tilted by Depth's gradient.
Eigen::Vector3d CarvingNormal(const SyntheticCarving& c, double u, double v) {
  const double e = 1e-3;
  const double du = (c.Depth(u + e, v) - c.Depth(u - e, v)) / (2 * e);
  const double dv = (c.Depth(u, v + e) - c.Depth(u, v - e)) / (2 * e);
  return (c.u_axis.cross(c.v_axis) + du * c.u_axis + dv * c.v_axis).normalized();
}

// A hit on a carved face continues into the recess: marched in steps that change the depth behind
// the face by at most depth/32 and move along it by at most 3 mm, then bisected to the surface.
void EnterCarving(const SyntheticScene& scene, const Eigen::Vector3d& o, const Eigen::Vector3d& dir, Hit* hit) {
  const Eigen::Vector3d x0 = o + hit->t * dir;
  for (const SyntheticCarving& c : scene.carvings) {
    if (c.solid != hit->primitive) continue;
    const Eigen::Vector3d n = c.u_axis.cross(c.v_axis);
    if (n.dot(hit->normal) < 0.999 || std::abs(n.dot(x0 - c.origin)) > 1e-6) continue;
    const double u0 = c.u_axis.dot(x0 - c.origin), v0 = c.v_axis.dot(x0 - c.origin);
    if (!(u0 > 0 && u0 < c.width && v0 > 0 && v0 < c.height)) continue;
    const double inward = -n.dot(dir);  // depth gained per unit t, > 0 for a ray entering
    if (!(inward > 0)) return;
    const double lateral = (dir + inward * n).norm();
    const double dt = std::min(c.depth / 32 / inward, lateral > 0 ? 0.003 / lateral : 1e300);
    // Empty (in the recess) while the depth behind the face is below the carving's depth there.
    const auto empty = [&](double t) {
      const Eigen::Vector3d d = o + t * dir - c.origin;
      return (t - hit->t) * inward < c.Depth(c.u_axis.dot(d), c.v_axis.dot(d));
    };
    double lo = hit->t, hi = hit->t;
    while (empty(hi)) lo = hi, hi += dt;
    if (hi == hit->t) return;  // on the frame: the face itself
    for (int i = 0; i < 40; ++i) {
      const double mid = 0.5 * (lo + hi);
      (empty(mid) ? lo : hi) = mid;
    }
    const Eigen::Vector3d d = o + hi * dir - c.origin;
    hit->t = hi;
    hit->normal = CarvingNormal(c, c.u_axis.dot(d), c.v_axis.dot(d));
    return;
  }
}

// Cyrus-Beck clipping of the ray against each convex solid; the nearest entry wins.
Hit CastRay(const SyntheticScene& scene, const Eigen::Vector3d& o, const Eigen::Vector3d& dir) {
  Hit best;
  for (size_t k = 0; k < scene.solids.size(); ++k) {
    const auto& planes = scene.solids[k].planes;
    double t_enter = -std::numeric_limits<double>::infinity();
    double t_exit = std::numeric_limits<double>::infinity();
    int enter_plane = -1;
    bool miss = false;
    for (size_t i = 0; i < planes.size() && !miss; ++i) {
      const auto& [n, d] = planes[i];
      const double denom = n.dot(dir), num = d - n.dot(o);
      if (denom == 0) {
        miss = num < 0;
      } else if (denom < 0) {
        if (num / denom > t_enter) t_enter = num / denom, enter_plane = static_cast<int>(i);
      } else {
        t_exit = std::min(t_exit, num / denom);
      }
    }
    if (miss || enter_plane < 0 || t_enter > t_exit || t_enter <= 1e-9) continue;
    if (best.t < 0 || t_enter < best.t) {
      best.t = t_enter;
      best.normal = planes[enter_plane].first;
      best.primitive = static_cast<int>(k);
    }
  }
  if (best.t > 0 && !scene.carvings.empty()) EnterCarving(scene, o, dir, &best);
  return best;
}

double LatticeValue(uint64_t seed, int64_t x, int64_t y, int64_t z) {
  const uint64_t key = (static_cast<uint64_t>(x) * 0x9E3779B1ULL) ^
                       (static_cast<uint64_t>(y) * 0x85EBCA77ULL << 21) ^
                       (static_cast<uint64_t>(z) * 0xC2B2AE3DULL << 42);
  return ToUnit(HashIndex(seed, key, 0x7e37));
}

// Trilinear value noise in [0, 1) on a lattice of spacing 1.
double ValueNoise(uint64_t seed, const Eigen::Vector3d& p) {
  const Eigen::Vector3d f = p.array().floor();
  const int64_t x = static_cast<int64_t>(f.x()), y = static_cast<int64_t>(f.y()),
                z = static_cast<int64_t>(f.z());
  const Eigen::Vector3d w = p - f;
  double v = 0;
  for (int c = 0; c < 8; ++c) {
    const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
    const double weight = (dx ? w.x() : 1 - w.x()) * (dy ? w.y() : 1 - w.y()) * (dz ? w.z() : 1 - w.z());
    v += weight * LatticeValue(seed, x + dx, y + dy, z + dz);
  }
  return v;
}

// 0 or 1 when x is on a marker (its quadrant's shade), else a negative value.
double MarkerShade(const SyntheticScene& scene, const Eigen::Vector3d& x, const Eigen::Vector3d& normal) {
  for (const SyntheticMarker& m : scene.markers) {
    const Eigen::Vector3d d = x - m.center;
    if (d.squaredNorm() > m.radius * m.radius || std::abs(d.dot(normal)) > 1e-3 * m.radius) continue;
    // In-plane axes: horizontal (or x on a horizontal surface) and the one across it.
    Eigen::Vector3d u = normal.cross(Eigen::Vector3d::UnitZ());
    if (u.norm() < 1e-6) u = Eigen::Vector3d::UnitX();
    u.normalize();
    const Eigen::Vector3d v = normal.cross(u);
    return (d.dot(u) >= 0) == (d.dot(v) >= 0) ? 0.0 : 1.0;
  }
  return -1;
}

Eigen::Vector3d Shade(const SyntheticScene& scene, const SyntheticViewsOptions& o,
                      const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) {
  const Hit hit = CastRay(scene, origin, dir);
  if (hit.t < 0) return Eigen::Vector3d::Zero();
  const Eigen::Vector3d x = origin + hit.t * dir;
  const double marker = MarkerShade(scene, x, hit.normal);
  if (marker >= 0) return Eigen::Vector3d::Constant(0.04 + 0.9 * marker);
  double texture = 1.0;
  if (!o.textureless) {
    const Eigen::Vector3d p = x / o.texture_cell;
    texture = 0.25 + 0.75 * (0.55 * ValueNoise(o.seed, p) + 0.3 * ValueNoise(o.seed + 1, p * 2.3) +
                             0.15 * ValueNoise(o.seed + 2, p * 0.37));
  }
  if (scene.block_size > 0) {  // stone blocks, each its own shade, courses offset by half a block
    const double b = scene.block_size;
    const int64_t row = static_cast<int64_t>(std::floor(x.z() / (0.5 * b)));
    const double shift = (row & 1) ? 0.5 * b : 0.0;
    texture *= 0.7 + 0.3 * LatticeValue(o.seed + 3, static_cast<int64_t>(std::floor((x.x() + shift) / b)),
                                        static_cast<int64_t>(std::floor((x.y() + shift) / b)), row);
  }
  const double lambert = scene.ambient + (1 - scene.ambient) * std::max(0.0, hit.normal.dot(scene.light));
  return scene.solids[hit.primitive].albedo * (texture * lambert);
}

PinholeCamera ArcCamera(const SyntheticViewsOptions& o, int k) {
  const double az = (-90.0 + (o.views > 1 ? o.arc_degrees * (k / (o.views - 1.0) - 0.5) : 0.0)) *
                    kPi / 180.0;
  const double el = o.elevation_degrees * kPi / 180.0;
  const Eigen::Vector3d target(0, 0, 0.35);
  const Eigen::Vector3d center =
      target + o.distance * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                            std::sin(el));
  return LookAtCamera(center, target, o.width, o.height, o.fov_degrees);
}

// A standard normal from two hashed uniforms (Box-Muller), stateless.
double HashNormal(uint64_t seed, uint64_t index, uint64_t stream) {
  const double u1 = std::max(ToUnit(HashIndex(seed, 2 * index, stream)), 1e-300);
  const double u2 = ToUnit(HashIndex(seed, 2 * index + 1, stream));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * kPi * u2);
}

SyntheticView RenderView(const SyntheticScene& scene, const SyntheticViewsOptions& o,
                         const PinholeCamera& camera, int k) {
  SyntheticView v;
  char name[96];
  std::snprintf(name, sizeof(name), "%s_%03d.png", o.name_prefix.c_str(), k);
  v.name = name;
  v.camera = camera;
  const int width = camera.width, height = camera.height;
  v.image = Image8(width, height, 3);
  v.depth = ImageF(width, height, 1, 0.0f);
  const Eigen::Matrix3d world_from_cam = v.camera.rotation.transpose();
  const Eigen::Vector3d origin = v.camera.Center();
  const int ss = o.supersample;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      for (int j = 0; j < ss; ++j)
        for (int i = 0; i < ss; ++i)
          sum += Shade(scene, o, origin, world_from_cam * v.camera.Ray(x + (i + 0.5) / ss, y + (j + 0.5) / ss));
      const Hit centre = CastRay(scene, origin, world_from_cam * v.camera.Ray(x + 0.5, y + 0.5));
      v.depth.at(x, y) = centre.t > 0 ? static_cast<float>(centre.t) : 0.0f;  // ray has z = 1
      for (int c = 0; c < 3; ++c) {
        double value = 255.0 * sum[c] / (ss * ss);
        if (o.noise_sigma > 0) {
          const uint64_t index = (static_cast<uint64_t>(y) * width + x) * 3 + c;
          value += o.noise_sigma * HashNormal(o.seed, index, 0x5eed0000ULL + k);
        }
        v.image.at(x, y, c) = static_cast<uint8_t>(std::clamp(std::lround(value), 0L, 255L));
      }
    }
  }
  return v;
}

// True when X is in frame and unoccluded in a view other than k.
bool SeenByAnother(const std::vector<SyntheticView>& views, size_t k, const Eigen::Vector3d& X) {
  for (size_t s = 0; s < views.size(); ++s) {
    if (s == k) continue;
    const PinholeCamera& c = views[s].camera;
    const Eigen::Vector3d p = c.ToCamera(X);
    if (!(p.z() > 0)) continue;
    const Eigen::Vector2d uv = c.Project(p);
    if (!(uv.x() >= 0 && uv.y() >= 0 && uv.x() < c.width && uv.y() < c.height)) continue;
    if (CastRay(TerracedBlockScene(), c.Center(), X - c.Center()).t > 1 - 1e-5) return true;
  }
  return false;
}

}  // namespace

void SyntheticViewsOptions::Check() const {
  CANDI_CHECK_OPTION_GE(views, 1);
  CANDI_CHECK_OPTION_GE(width, 8);
  CANDI_CHECK_OPTION_GE(height, 8);
  CANDI_CHECK_OPTION(arc_degrees >= 0 && arc_degrees < 360, arc_degrees, "in [0, 360)");
  CANDI_CHECK_OPTION(elevation_degrees > 0 && elevation_degrees < 90, elevation_degrees,
                     "in (0, 90)");
  CANDI_CHECK_OPTION_GT(distance, 2);
  CANDI_CHECK_OPTION(fov_degrees > 5 && fov_degrees < 150, fov_degrees, "in (5, 150)");
  CANDI_CHECK_OPTION_GT(texture_cell, 0);
  CANDI_CHECK_OPTION_IN(supersample, 1, 8);
  CANDI_CHECK_OPTION_GE(noise_sigma, 0);
}

SyntheticSolid SyntheticBox(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, const Eigen::Vector3d& albedo) {
  CANDI_CHECK((lo.array() < hi.array()).all()) << "an empty box";
  SyntheticSolid c;
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    n[a] = 1;
    c.planes.push_back({n, hi[a]});
    c.planes.push_back({-n, -lo[a]});
  }
  c.albedo = albedo;
  return c;
}

double SyntheticCarving::Depth(double u, double v) const {
  if (!(u > 0 && u < width && v > 0 && v < height)) return 0;
  // The frame: the face at the border, ramping down to the background over `ramp`.
  const double frame = std::min(0.06, 0.1 * std::min(width, height)), ramp = 0.5 * frame;
  const double edge = std::min(std::min(u, width - u), std::min(v, height - v));
  const double cut = SmoothStep((edge - frame) / ramp + 1.0);
  if (cut == 0) return 0;
  // Figures: about 3 a square metre, 0.07-0.15 m wide and twice as tall, in rows.
  const int figures = std::max(1, static_cast<int>(std::lround(3.0 * width * height)));
  double relief = 0;
  for (int i = 0; i < figures; ++i) {
    const double fu = frame + (width - 2 * frame) * ToUnit(HashIndex(seed, i, 0xf1));
    const double fv = frame + (height - 2 * frame) * (0.3 + 0.4 * ToUnit(HashIndex(seed, i, 0xf2)));
    const double su = 0.07 + 0.08 * ToUnit(HashIndex(seed, i, 0xf3)), sv = 2 * su;
    const double q = (u - fu) * (u - fu) / (su * su) + (v - fv) * (v - fv) / (sv * sv);
    if (q < 9) relief += std::exp(-0.5 * q);
  }
  return depth * cut * (1.0 - 0.85 * std::min(1.0, relief));
}

// The ground, two terraces, a ramp (its slanted face rises from x = 1.6 to the lower terrace's top
// at x = 1).
const SyntheticScene& TerracedBlockScene() {
  static const SyntheticScene scene = [] {
    SyntheticScene s;
    s.solids.push_back(SyntheticBox({-40, -40, -1}, {40, 40, 0}, {0.55, 0.50, 0.42}));
    s.solids.push_back(SyntheticBox({-1.0, -1.0, 0}, {1.0, 1.0, 0.5}, {0.78, 0.70, 0.60}));
    s.solids.push_back(SyntheticBox({-0.55, -0.55, 0}, {0.55, 0.55, 0.9}, {0.70, 0.72, 0.75}));
    SyntheticSolid ramp = SyntheticBox({1.0, -1.0, 0}, {1.6, 1.0, 0.5}, {0.72, 0.62, 0.50});
    ramp.planes.push_back({Eigen::Vector3d(5.0 / 6.0, 0, 1).normalized(),
                           (4.0 / 3.0) / Eigen::Vector3d(5.0 / 6.0, 0, 1).norm()});
    s.solids.push_back(ramp);
    return s;
  }();
  return scene;
}

double SyntheticScene::RayHit(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
  return CastRay(*this, origin, direction).t;
}

bool SyntheticScene::Sees(const PinholeCamera& camera, const Eigen::Vector3d& point) const {
  const Eigen::Vector3d p = camera.ToCamera(point);
  if (!(p.z() > 0)) return false;
  const Eigen::Vector2d uv = camera.Project(p);
  if (!(uv.x() >= 0 && uv.y() >= 0 && uv.x() < camera.width && uv.y() < camera.height)) return false;
  const double t = RayHit(camera.Center(), point - camera.Center());
  return t > 0 && std::abs(1.0 - t) < 1e-6;
}

PinholeCamera LookAtCamera(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, int width,
                           int height, double fov_degrees) {
  const Eigen::Vector3d forward = (target - eye).normalized();
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  CANDI_CHECK(right.allFinite()) << "a camera looking straight up or down";
  const Eigen::Vector3d down = forward.cross(right);
  PinholeCamera c;
  c.width = width;
  c.height = height;
  c.fx = c.fy = 0.5 * width / std::tan(0.5 * fov_degrees * kPi / 180.0);
  c.cx = 0.5 * width;
  c.cy = 0.5 * height;
  c.rotation.row(0) = right;
  c.rotation.row(1) = down;
  c.rotation.row(2) = forward;
  c.translation = -c.rotation * eye;
  return c;
}

std::vector<SyntheticView> RenderSyntheticViews(const SyntheticViewsOptions& options) {
  options.Check();
  std::vector<PinholeCamera> cameras;
  for (int k = 0; k < options.views; ++k) cameras.push_back(ArcCamera(options, k));
  return RenderSyntheticScene(TerracedBlockScene(), cameras, options);
}

SyntheticView RenderSyntheticView(const SyntheticScene& scene, const PinholeCamera& camera,
                                  const SyntheticViewsOptions& options, int index) {
  options.Check();
  return RenderView(scene, options, camera, index);
}

std::vector<SyntheticView> RenderSyntheticScene(const SyntheticScene& scene,
                                                const std::vector<PinholeCamera>& cameras,
                                                const SyntheticViewsOptions& options) {
  options.Check();
  std::vector<SyntheticView> views(cameras.size());
  ParallelFor(size_t{0}, cameras.size(), [&](size_t k) {
    views[k] = RenderView(scene, options, cameras[k], static_cast<int>(k));
  });
  return views;
}

double SyntheticSceneRayHit(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) {
  return CastRay(TerracedBlockScene(), origin, direction).t;
}

std::vector<Eigen::Vector3d> SyntheticSparsePoints(const std::vector<SyntheticView>& views,
                                                   int stride) {
  std::vector<Eigen::Vector3d> points;
  for (const SyntheticView& v : views) {
    for (int y = stride / 2; y < v.depth.height(); y += stride) {
      for (int x = stride / 2; x < v.depth.width(); x += stride) {
        const double d = v.depth.at(x, y);
        if (d > 0) points.push_back(v.camera.ToWorld(d * v.camera.Ray(x + 0.5, y + 0.5)));
      }
    }
  }
  return points;
}

SyntheticDenseScore ScoreSyntheticDense(const std::vector<SyntheticView>& views,
                                        const std::vector<ImageF>& depths,
                                        const std::vector<Eigen::Vector3d>& points,
                                        double tolerance) {
  CANDI_CHECK(depths.size() == views.size()) << depths.size() << " depth maps for " << views.size();
  SyntheticDenseScore score;
  score.points = points.size();
  std::vector<double> errors;
  for (const Eigen::Vector3d& p : points) {
    double best = std::numeric_limits<double>::infinity();
    for (const SyntheticView& v : views) {
      const Eigen::Vector3d c = v.camera.ToCamera(p);
      if (!(c.z() > 0)) continue;
      const Eigen::Vector2d uv = v.camera.Project(c);
      if (!(uv.x() >= 0 && uv.y() >= 0 && uv.x() < v.camera.width && uv.y() < v.camera.height)) continue;
      const Eigen::Vector3d origin = v.camera.Center(), dir = p - origin;
      const double t = CastRay(TerracedBlockScene(), origin, dir).t;  // 1 = at p
      if (t > 0) best = std::min(best, std::abs(1.0 - t));
    }
    errors.push_back(best);
  }
  size_t good = 0;
  for (double e : errors) good += e <= tolerance;
  score.accuracy = points.empty() ? 0.0 : static_cast<double>(good) / points.size();
  if (!errors.empty()) {
    std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
    score.median_error = errors[errors.size() / 2];
  }
  uint64_t with_truth = 0, correct = 0, observable = 0, observable_correct = 0;
  for (size_t k = 0; k < views.size(); ++k) {
    const ImageF& truth = views[k].depth;
    const ImageF& d = depths[k];
    if (d.empty()) continue;
    for (int y = 0; y < d.height(); ++y) {
      for (int x = 0; x < d.width(); ++x) {
        const int tx = std::min(truth.width() - 1, static_cast<int>((x + 0.5) * truth.width() / d.width()));
        const int ty = std::min(truth.height() - 1, static_cast<int>((y + 0.5) * truth.height() / d.height()));
        const double t = truth.at(tx, ty);
        if (!(t > 0)) continue;
        ++with_truth;
        const bool ok = d.at(x, y) > 0 && std::abs(d.at(x, y) - t) <= tolerance * t;
        correct += ok;
        const Eigen::Vector3d X = views[k].camera.ToWorld(t * views[k].camera.Ray(tx + 0.5, ty + 0.5));
        if (SeenByAnother(views, k, X)) ++observable, observable_correct += ok;
      }
    }
  }
  score.completeness_all = with_truth ? static_cast<double>(correct) / with_truth : 0.0;
  score.completeness = observable ? static_cast<double>(observable_correct) / observable : 0.0;
  return score;
}

void WriteSyntheticImages(const std::vector<SyntheticView>& views, const std::string& dir) {
  std::filesystem::create_directories(dir);
  for (const SyntheticView& v : views) io::WritePng((std::filesystem::path(dir) / v.name).string(), v.image);
}

}  // namespace candi::photogrammetry

#include "reconstruction/relief/relief_synth.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>

#include "core/check.h"
#include "core/rng.h"
#include "reconstruction/relief/relief_image.h"

namespace candi::relief {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// Value noise on an integer lattice (cell = 1), smooth (C1) interpolation, values in [-1, 1].
double ValueNoise(uint64_t seed, double x, double y) {
  const double fx = std::floor(x), fy = std::floor(y);
  const int64_t ix = static_cast<int64_t>(fx), iy = static_cast<int64_t>(fy);
  auto lattice = [&](int64_t i, int64_t j) {
    return 2.0 * ToUnit(HashIndex(seed, static_cast<uint64_t>(i) * 0x9E3779B1ULL ^
                                            static_cast<uint64_t>(j))) - 1.0;
  };
  auto smooth = [](double t) { return t * t * (3 - 2 * t); };
  const double tx = smooth(x - fx), ty = smooth(y - fy);
  const double a = lattice(ix, iy) + tx * (lattice(ix + 1, iy) - lattice(ix, iy));
  const double b = lattice(ix, iy + 1) + tx * (lattice(ix + 1, iy + 1) - lattice(ix, iy + 1));
  return a + ty * (b - a);
}

// Fractal sum of `octaves` value-noise octaves; `cell` is the coarsest feature size (same unit
// as x, y). Roughly in [-1, 1].
double Fbm(uint64_t seed, double x, double y, double cell, int octaves) {
  double sum = 0, amplitude = 0.5, norm = 0;
  for (int o = 0; o < octaves; ++o) {
    sum += amplitude * ValueNoise(seed + o, x / cell, y / cell);
    norm += amplitude;
    amplitude *= 0.5;
    cell *= 0.5;
  }
  return sum / norm;
}

// Raster of a panel in metres: pixel (i, j) has centre ((i + 0.5) p, (j + 0.5) p), y down.
struct Canvas {
  ImageF* h;
  double pixel_m;
  // Raises h to f(x, y) inside the box [x0, x1] x [y0, y1] (metres); f < 0 means "outside".
  void Stamp(double x0, double y0, double x1, double y1,
             const std::function<double(double, double)>& f) const {
    const int i0 = std::max(0, static_cast<int>(x0 / pixel_m));
    const int j0 = std::max(0, static_cast<int>(y0 / pixel_m));
    const int i1 = std::min(h->width() - 1, static_cast<int>(x1 / pixel_m) + 1);
    const int j1 = std::min(h->height() - 1, static_cast<int>(y1 / pixel_m) + 1);
    for (int j = j0; j <= j1; ++j) {
      for (int i = i0; i <= i1; ++i) {
        const double v = f((i + 0.5) * pixel_m, (j + 0.5) * pixel_m);
        if (v > h->at(i, j)) h->at(i, j) = static_cast<float>(v);
      }
    }
  }
};

// Carved profile: flat top, steep rounded edge. t = normalised distance from the axis, [0, 1).
double Profile(double t, double top) {
  return t >= 1.0 ? -1.0 : top * std::pow(1.0 - std::pow(t, 4.0), 0.35);
}

// A rounded limb from a to b (radius r, top height); `folds` cuts clothing grooves (m).
void Capsule(const Canvas& c, double ax, double ay, double bx, double by, double r, double top,
             double folds = 0) {
  const double dx = bx - ax, dy = by - ay, len2 = std::max(dx * dx + dy * dy, 1e-12);
  c.Stamp(std::min(ax, bx) - r, std::min(ay, by) - r, std::max(ax, bx) + r, std::max(ay, by) + r,
          [=](double x, double y) {
            const double s = std::clamp(((x - ax) * dx + (y - ay) * dy) / len2, 0.0, 1.0);
            const double ex = x - ax - s * dx, ey = y - ay - s * dy;
            const double v = Profile(std::sqrt(ex * ex + ey * ey) / r, top);
            return v < 0 ? v : v - folds * std::max(0.0, std::sin(s * 7 * kPi + ex / r * 2));
          });
}

void Ellipse(const Canvas& c, double cx, double cy, double rx, double ry, double top) {
  c.Stamp(cx - rx, cy - ry, cx + rx, cy + ry, [=](double x, double y) {
    const double u = (x - cx) / rx, v = (y - cy) / ry;
    return Profile(std::sqrt(u * u + v * v), top);
  });
}

void Ring(const Canvas& c, double cx, double cy, double r, double width, double top) {
  c.Stamp(cx - r - width, cy - r - width, cx + r + width, cy + r + width, [=](double x, double y) {
    const double d = std::hypot(x - cx, y - cy);
    return Profile(std::abs(d - r) / width, top);
  });
}

// A figure standing on `foot_y` (metres, y down) of height `s`, relief top `top`.
void Figure(const Canvas& c, Rng& rng, double x0, double foot_y, double s, double top) {
  const bool seated = rng.Uniform() < 0.35;
  const double hip_y = foot_y - (seated ? 0.25 : 0.45) * s, neck_y = foot_y - (seated ? 0.7 : 0.84) * s;
  const double lean = rng.Uniform(-0.06, 0.06) * s;
  const double head_r = 0.075 * s;
  Ellipse(c, x0 + lean, neck_y - head_r * 0.9, head_r * 0.85, head_r, top);
  if (rng.Uniform() < 0.6) Ellipse(c, x0 + lean, neck_y - 2.1 * head_r, head_r * 0.6, head_r * 0.5, top * 0.95);
  if (rng.Uniform() < 0.3) Ring(c, x0 + lean, neck_y - head_r, head_r * 1.5, 0.012 * s, top * 0.6);
  Capsule(c, x0 + lean, neck_y, x0, hip_y, 0.1 * s, top * 0.92, 0.004);
  for (int side : {-1, 1}) {
    const double sx = x0 + lean + side * 0.1 * s, sy = neck_y + 0.04 * s;
    const double a1 = rng.Uniform(0.2, 1.6), a2 = a1 + rng.Uniform(-1.2, 1.2);
    const double ex = sx + side * std::sin(a1) * 0.2 * s, ey = sy + std::cos(a1) * 0.2 * s;
    Capsule(c, sx, sy, ex, ey, 0.035 * s, top * rng.Uniform(0.85, 1.0));
    Capsule(c, ex, ey, ex + side * std::sin(a2) * 0.17 * s, ey + std::cos(a2) * 0.17 * s,
            0.03 * s, top * rng.Uniform(0.85, 1.0));
  }
  for (int side : {-1, 1}) {
    const double hx = x0 + side * 0.05 * s;
    if (seated) {
      const double kx = hx + side * 0.2 * s;
      Capsule(c, hx, hip_y, kx, hip_y + 0.02 * s, 0.05 * s, top * 0.85, 0.003);
      Capsule(c, kx, hip_y + 0.02 * s, kx - side * 0.04 * s, foot_y, 0.045 * s, top * 0.8);
    } else {
      Capsule(c, hx, hip_y, hx + side * rng.Uniform(0.0, 0.08) * s, foot_y, 0.05 * s, top * 0.85, 0.003);
    }
  }
}

void Tree(const Canvas& c, Rng& rng, double x0, double foot_y, double s, double top) {
  Capsule(c, x0, foot_y, x0 + rng.Uniform(-0.03, 0.03), foot_y - 0.55 * s, 0.03 * s, top);
  const int blobs = 4 + static_cast<int>(rng.Below(5));
  for (int k = 0; k < blobs; ++k) {
    Ellipse(c, x0 + rng.Uniform(-0.22, 0.22) * s, foot_y - rng.Uniform(0.55, 0.95) * s,
            rng.Uniform(0.06, 0.14) * s, rng.Uniform(0.05, 0.1) * s, top * rng.Uniform(0.7, 1.0));
  }
}

void Rosette(const Canvas& c, Rng& rng, double cx, double cy, double r, double top) {
  Ellipse(c, cx, cy, 0.3 * r, 0.3 * r, top);
  const int petals = 5 + static_cast<int>(rng.Below(4));
  for (int k = 0; k < petals; ++k) {
    const double a = 2 * kPi * k / petals;
    Ellipse(c, cx + 0.65 * r * std::cos(a), cy + 0.65 * r * std::sin(a), 0.28 * r, 0.28 * r, top * 0.8);
  }
}

// The raised frame along the top and bottom edges.
void Frame(const Canvas& c, double w, double h, double band, double top) {
  for (double y0 : {0.0, h - band}) {
    c.Stamp(0, y0, w, y0 + band, [=](double, double y) {
      const double t = std::abs(y - (y0 + band / 2)) / (band / 2);
      return Profile(std::min(t, 0.999), top);
    });
  }
}

// Cast-shadow sweep along x: S(x) = max(h(x), S(x + sx) - drop), sampling the neighbour column
// at y + dy (linear). Returns the light's clearance above each pixel (> 0: in shadow), metres.
ImageF ShadowSweepX(const ImageF& h, int sx, double dy, double drop) {
  const int w = h.width(), ht = h.height();
  ImageF s(w, ht, 1), clearance(w, ht, 1, 0.0f);
  const int first = sx > 0 ? w - 1 : 0;
  for (int k = 0; k < w; ++k) {
    const int x = first - sx * k;
    for (int y = 0; y < ht; ++y) {
      float v = h.at(x, y);
      if (k > 0) {
        const double yy = std::clamp(y + dy, 0.0, ht - 1.0);
        const int y0 = static_cast<int>(yy), y1 = std::min(y0 + 1, ht - 1);
        const double f = yy - y0;
        const double upstream = (1 - f) * s.at(x + sx, y0) + f * s.at(x + sx, y1) - drop;
        clearance.at(x, y) = static_cast<float>(upstream - v);
        v = std::max<float>(v, static_cast<float>(upstream));
      }
      s.at(x, y) = v;
    }
  }
  return clearance;
}

ImageF Transposed(const ImageF& a) {
  ImageF t(a.height(), a.width(), 1);
  for (int y = 0; y < a.height(); ++y) {
    for (int x = 0; x < a.width(); ++x) t.at(y, x) = a.at(x, y);
  }
  return t;
}

// Light clearance above each pixel for a light at azimuth/elevation (radians), image y down.
ImageF ShadowClearance(const ImageF& h, double pixel_m, double azimuth, double elevation) {
  const double lx = std::cos(azimuth), ly = -std::sin(azimuth);  // towards the light, image axes
  const double tan_e = std::tan(elevation);
  if (std::abs(lx) >= std::abs(ly)) {
    const double dy = ly / std::abs(lx);
    return ShadowSweepX(h, lx > 0 ? 1 : -1, dy, pixel_m * std::hypot(1.0, dy) * tan_e);
  }
  const double dx = lx / std::abs(ly);
  return Transposed(ShadowSweepX(Transposed(h), ly > 0 ? 1 : -1, dx,
                                 pixel_m * std::hypot(1.0, dx) * tan_e));
}

// Lambertian shading with cast shadows; ambient term `ambient`.
ImageF Shade(const OldPhotoOptions& o, const ImageF& h, double pixel_m, double az, double el,
             double ambient) {
  const int w = h.width(), ht = h.height();
  const double L[3] = {std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  ImageF clearance = o.shadows ? ShadowClearance(h, pixel_m, az, el) : ImageF(w, ht, 1, -1.0f);
  ImageF shade(w, ht, 1);
  for (int y = 0; y < ht; ++y) {
    for (int x = 0; x < w; ++x) {
      const double dzdx = (h.at(std::min(x + 1, w - 1), y) - h.at(std::max(x - 1, 0), y)) / (2 * pixel_m);
      const double dzdrow = (h.at(x, std::min(y + 1, ht - 1)) - h.at(x, std::max(y - 1, 0))) / (2 * pixel_m);
      const double n[3] = {-dzdx, dzdrow, 1.0};  // y up = -row
      const double ndotl = (n[0] * L[0] + n[1] * L[1] + n[2] * L[2]) /
                           std::sqrt(n[0] * n[0] + n[1] * n[1] + 1.0);
      const double lit = 1.0 - std::clamp(clearance.at(x, y) / 0.001, 0.0, 1.0);  // 1 mm penumbra
      shade.at(x, y) = static_cast<float>(ambient + (1 - ambient) * std::max(0.0, ndotl) * lit);
    }
  }
  return shade;
}

// Tone curve, fading and vignetting, applied per pixel to v in [0, 1].
void Develop(const OldPhotoOptions& o, Rng& rng, ImageF* photo) {
  const double gamma = o.tone ? rng.Uniform(0.7, 1.4) : 1.0;
  const double s_curve = o.tone ? rng.Uniform(0.0, 0.5) : 0.0;
  const double contrast = o.fading ? rng.Uniform(0.55, 0.9) : 1.0;
  const double base = o.fading ? rng.Uniform(0.45, 0.65) : 0.5;
  const double vignette = o.fading ? rng.Uniform(0.0, 0.35) : 0.0;
  const int w = photo->width(), h = photo->height();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double v = std::pow(std::clamp<double>(photo->at(x, y), 0.0, 1.0), gamma);
      v += s_curve * (v - 0.5) * (1 - std::abs(2 * v - 1));  // steeper mid-tones
      v = base + contrast * (v - 0.5);
      const double rx = (x + 0.5) / w * 2 - 1, ry = (y + 0.5) / h * 2 - 1;
      v *= 1 - vignette * (rx * rx + ry * ry) / 2;
      photo->at(x, y) = static_cast<float>(v);
    }
  }
}

}  // namespace

void OldPhotoOptions::Check() const {
  CANDI_CHECK_OPTION_PAIR(
      light_elevation_min_deg > 0 && light_elevation_min_deg <= light_elevation_max_deg &&
          light_elevation_max_deg < 90,
      light_elevation_min_deg, light_elevation_max_deg, "must satisfy 0 < min <= max < 90");
  CANDI_CHECK_OPTION_LE(light_azimuth_min_deg, light_azimuth_max_deg);
}

void SynthOptions::Check() const {
  CANDI_CHECK_OPTION_IN(width, 32, 16384);
  CANDI_CHECK_OPTION(width_m > 0 && std::isfinite(width_m), width_m, "> 0");
  CANDI_CHECK_OPTION(height_m > 0 && std::isfinite(height_m), height_m, "> 0");
  CANDI_CHECK_OPTION(depth_m > 0 && std::isfinite(depth_m), depth_m, "> 0");
  CANDI_CHECK_OPTION(Height() >= 32, height_m / width_m * width, ">= 32 pixels (rounded)");
  photo.Check();
}

int SynthOptions::Height() const {
  return std::max(1, static_cast<int>(std::lround(width * height_m / width_m)));
}

ImageF ReliefHeightField(const SynthOptions& o, uint64_t index) {
  o.Check();
  Rng rng(HashIndex(o.seed, index, 1));
  ImageF h(o.width, o.Height(), 1, 0.0f);
  const Canvas c{&h, o.PixelM()};
  const double W = o.width_m, H = o.height_m, D = o.depth_m * 0.97;
  const double band = H * rng.Uniform(0.06, 0.1);
  Frame(c, W, H, band, D * rng.Uniform(0.75, 1.0));
  const double floor_y = H - band, inner = H - 2 * band;
  const int figures = 3 + static_cast<int>(rng.Below(4));
  for (int k = 0; k < figures; ++k) {
    const double x = W * (k + 0.5 + rng.Uniform(-0.2, 0.2)) / figures;
    Figure(c, rng, x, floor_y - 0.02, inner * rng.Uniform(0.75, 0.95), D * rng.Uniform(0.45, 1.0));
    const double between = W * (k + 1.0) / figures;
    const double pick = rng.Uniform();
    if (k + 1 < figures && pick < 0.5) {
      Tree(c, rng, between, floor_y, inner * rng.Uniform(0.6, 0.9), D * rng.Uniform(0.3, 0.6));
    } else if (k + 1 < figures && pick < 0.8) {
      Rosette(c, rng, between, band + inner * rng.Uniform(0.2, 0.4), inner * 0.08, D * rng.Uniform(0.3, 0.6));
    } else if (k + 1 < figures) {
      Ellipse(c, between, floor_y - inner * 0.1, inner * 0.07, inner * 0.1, D * rng.Uniform(0.3, 0.7));
    }
  }
  // Weathering: millimetre roughness, then rounding of sharp edges (sigma 1.5 mm).
  const uint64_t noise_seed = HashIndex(o.seed, index, 2);
  for (int y = 0; y < h.height(); ++y) {
    for (int x = 0; x < h.width(); ++x) {
      const double r = 0.0015 * Fbm(noise_seed, (x + 0.5) * c.pixel_m, (y + 0.5) * c.pixel_m, 0.05, 4);
      h.at(x, y) = static_cast<float>(std::clamp(h.at(x, y) + 0.0015 + r, 0.0, D));
    }
  }
  return GaussianBlur(h, 0.0015 / c.pixel_m);
}

ImageF StoneAlbedo(const OldPhotoOptions& o, int width, int height, double pixel_m, uint64_t seed) {
  ImageF albedo(width, height, 1, 0.6f);
  if (!o.stains) return albedo;
  Rng rng(HashIndex(seed, 0, 3));
  const double base = rng.Uniform(0.45, 0.7);
  const int stains = 2 + static_cast<int>(rng.Below(5));
  struct Stain { double x, y, r, dark; };
  std::vector<Stain> list;
  for (int k = 0; k < stains; ++k) {
    list.push_back({rng.Uniform(0, width * pixel_m), rng.Uniform(0, height * pixel_m),
                    rng.Uniform(0.05, 0.3), rng.Uniform(0.15, 0.45)});
  }
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const double px = (x + 0.5) * pixel_m, py = (y + 0.5) * pixel_m;
      double a = base * (1 + 0.15 * Fbm(seed + 11, px, py, 0.08, 5));
      for (const Stain& s : list) {
        const double d = std::hypot(px - s.x, py - s.y) / s.r + 0.4 * Fbm(seed + 17, px, py, 0.1, 3);
        if (d < 1) a *= 1 - s.dark * (1 - d * d);
      }
      albedo.at(x, y) = static_cast<float>(std::clamp(a, 0.0, 1.0));
    }
  }
  return albedo;
}

PhotoSimulation SimulateOldPhoto(const OldPhotoOptions& o, const ImageF& height_m,
                                 const ImageF& albedo, double pixel_m, uint64_t seed) {
  o.Check();
  CANDI_CHECK(pixel_m > 0) << pixel_m;
  CANDI_CHECK(albedo.empty() || (albedo.width() == height_m.width() && albedo.height() == height_m.height()));
  Rng rng(HashIndex(seed, 0, 4));
  PhotoSimulation out;
  out.light_azimuth_deg = rng.Uniform(o.light_azimuth_min_deg, o.light_azimuth_max_deg);
  out.light_elevation_deg = rng.Uniform(o.light_elevation_min_deg, o.light_elevation_max_deg);
  const double ambient = rng.Uniform(0.12, 0.3);
  ImageF photo = Shade(o, height_m, pixel_m, out.light_azimuth_deg * kDeg,
                       out.light_elevation_deg * kDeg, ambient);
  for (size_t i = 0; i < photo.values().size(); ++i) {
    photo.values()[i] *= albedo.empty() ? 0.6f : albedo.values()[i];
  }
  // Normalise the exposure so the brightest 1 % is near white, like a printed photo.
  std::vector<float> sorted = photo.values();
  const size_t k = sorted.size() * 99 / 100;
  std::nth_element(sorted.begin(), sorted.begin() + k, sorted.end());
  const float gain = sorted[k] > 1e-6f ? 0.95f / sorted[k] : 1.0f;
  for (float& v : photo.values()) v *= gain;
  if (o.blur) photo = GaussianBlur(photo, rng.Uniform(0.0005, 0.002) / pixel_m);
  Develop(o, rng, &photo);
  if (o.grain) {
    const double sigma = rng.Uniform(0.01, 0.04);
    ImageF grain(photo.width(), photo.height(), 1);
    Rng noise(HashIndex(seed, 0, 5));
    for (float& g : grain.values()) g = static_cast<float>(noise.Normal());
    grain = GaussianBlur(grain, 0.6);  // clumps of about a pixel; the blur halves the variance
    for (size_t i = 0; i < photo.values().size(); ++i) {
      photo.values()[i] += static_cast<float>(2.0 * sigma * grain.values()[i]);
    }
  }
  for (float& v : photo.values()) v = std::clamp(v, 0.0f, 1.0f);
  out.photo = std::move(photo);
  return out;
}

SynthPanel SynthesizePanel(const SynthOptions& o, uint64_t index) {
  SynthPanel p;
  p.pixel_m = o.PixelM();
  p.height_m = ReliefHeightField(o, index);
  const uint64_t seed = HashIndex(o.seed, index, 6);
  p.albedo = StoneAlbedo(o.photo, p.height_m.width(), p.height_m.height(), p.pixel_m, seed);
  p.photo = SimulateOldPhoto(o.photo, p.height_m, p.albedo, p.pixel_m, seed);
  p.depth = ImageF(p.height_m.width(), p.height_m.height(), 1);
  for (size_t i = 0; i < p.depth.values().size(); ++i) {
    p.depth.values()[i] = static_cast<float>(LevelFromHeight(p.height_m.values()[i], o.depth_m));
  }
  return p;
}

}  // namespace candi::relief

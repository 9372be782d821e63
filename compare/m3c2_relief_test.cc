// M3C2 on a carved relief panel from candi's own generator (relief_synth.h), as Lague, Brodu &
// Leroux (2013) describe it for rough surfaces. Two surveys of the default panel (2.7 x 0.92 m,
// carving up to 0.15 m), each on its own jittered 2 cm grid with 1 mm Gaussian noise along the
// panel normal; in the second a band has moved 10 mm out of the wall. With the normal scale D about
// 20-25 times the roughness at that scale (the paper's rule; D = 1 m, roughness ~4.6 cm here) the
// normals are the panel's: the band reads 10 mm and at most ~5 % of the unchanged part is flagged
// (95 % level). The carving within the projection scale d enters the spreads s1, s2, so LoD95 is
// far above a flat plane's with the same noise, and it is 1.96 (sqrt(s1^2/n1 + s2^2/n2) + reg)
// with s, n recounted here from the points. With D at the figures' scale (D / roughness ~14) the
// normals follow their flanks and the band's move reads short: why the paper sizes D by roughness.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "compare/deviation.h"
#include "core/rng.h"
#include "reconstruction/relief/relief_synth.h"

namespace candi::compare {
namespace {

constexpr double kNoise = 0.001;                // survey noise along the panel normal, m
constexpr double kShift = 0.010;                // the band's move out of the wall, m
constexpr double kBandX0 = 1.0, kBandX1 = 1.6;  // the band that moves, m along the panel
constexpr double kSpacing = 0.02;               // survey grid, m
constexpr double kNormalScale = 1.0;            // D, m
constexpr double kProjectionScale = 0.12;       // d, m: ~28 points of a survey in a cylinder
constexpr double kMaxDepth = 0.2;               // the cylinder's half-length: spans the carving
// Core points this close to the band's edges are in neither region: their cylinders (d / 2 = 6 cm)
// straddle the edge.
constexpr double kMargin = 0.08;

// The generator's first panel at 5 mm pixels (the default panel, seed 1).
relief::SynthOptions PanelOptions() {
  relief::SynthOptions o;
  o.width = 540;
  return o;
}

// The height field (metres; pixel_m per pixel) at (x, y) m from its top-left corner, bilinear
// between pixel centres.
double HeightAt(const ImageF& height_m, double pixel_m, double x, double y) {
  const double u = std::clamp(x / pixel_m - 0.5, 0.0, height_m.width() - 1.0);
  const double v = std::clamp(y / pixel_m - 0.5, 0.0, height_m.height() - 1.0);
  const int i = std::min(static_cast<int>(u), height_m.width() - 2);
  const int j = std::min(static_cast<int>(v), height_m.height() - 2);
  const double a = u - i, b = v - j;
  return (1 - b) * ((1 - a) * height_m.at(i, j) + a * height_m.at(i + 1, j)) +
         b * ((1 - a) * height_m.at(i, j + 1) + a * height_m.at(i + 1, j + 1));
}

// One survey: a jittered kSpacing grid over the panel (x along it, y down from its top edge, z out
// of the wall), z with Gaussian noise kNoise; points with x in [kBandX0, kBandX1) raised by
// `shift`.
PointCloud Survey(const ImageF& height_m, double pixel_m, double shift, uint64_t seed) {
  Rng rng(seed);
  PointCloud cloud;
  const int nx = static_cast<int>(height_m.width() * pixel_m / kSpacing);
  const int ny = static_cast<int>(height_m.height() * pixel_m / kSpacing);
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const double x = (i + rng.Uniform()) * kSpacing, y = (j + rng.Uniform()) * kSpacing;
      const double moved = x >= kBandX0 && x < kBandX1 ? shift : 0.0;
      cloud.positions.emplace_back(
          x, y, HeightAt(height_m, pixel_m, x, y) + moved + kNoise * rng.Normal());
    }
  }
  return cloud;
}

DeviationResult RunM3c2(const PointCloud& reference, const PointCloud& compared,
                        double normal_scale) {
  DeviationOptions o;
  o.method = Method::kM3C2;
  o.m3c2.normal_scale = normal_scale;
  o.m3c2.projection_scale = kProjectionScale;
  o.m3c2.max_depth = kMaxDepth;
  return CompareToCloud(o, reference, compared, "survey-1", "survey-2");
}

// Over the core points with a distance in one region: their count, mean distance, and the shares
// flagged significant and with a normal more than 10 degrees off the panel's.
struct Region {
  size_t n = 0;
  double mean = 0, significant_share = 0, tilted_share = 0;
};

// The band's interior (`in_band`) or the panel well outside it.
Region Summarise(const DeviationResult& r, const PointCloud& compared, bool in_band) {
  Region s;
  for (size_t i = 0; i < r.distance.size(); ++i) {
    const double x = compared.positions[i].x();
    const bool inside = x >= kBandX0 + kMargin && x < kBandX1 - kMargin;
    const bool outside = x < kBandX0 - kMargin || x >= kBandX1 + kMargin;
    if (std::isnan(r.distance[i]) || !(in_band ? inside : outside)) continue;
    ++s.n;
    s.mean += r.distance[i];
    s.significant_share += r.significant[i];
    s.tilted_share += r.normals[i].z() < std::cos(10 * M_PI / 180) ? 1 : 0;
  }
  s.mean /= s.n;
  s.significant_share /= s.n;
  s.tilted_share /= s.n;
  return s;
}

double MedianLod(const DeviationResult& r) {
  std::vector<double> lod;
  for (double v : r.lod95) {
    if (!std::isnan(v)) lod.push_back(v);
  }
  std::nth_element(lod.begin(), lod.begin() + lod.size() / 2, lod.end());
  return lod[lod.size() / 2];
}

// The points of `cloud` in the cylinder through q along unit n (radius d / 2, half-length
// kMaxDepth), recounted by brute force: how many, their mean and sample standard deviation along n.
struct Cylinder {
  size_t n = 0;
  double mean = 0, std = 0;
};
Cylinder Recount(const PointCloud& cloud, const Eigen::Vector3d& q, const Eigen::Vector3d& n) {
  std::vector<double> along;
  for (const Eigen::Vector3d& p : cloud.positions) {
    const double t = n.dot(p - q);
    const bool inside = std::abs(t) <= kMaxDepth && (p - q - t * n).norm() <= kProjectionScale / 2;
    if (inside) along.push_back(t);
  }
  Cylinder c;
  c.n = along.size();
  for (double t : along) c.mean += t / c.n;
  for (double t : along) c.std += (t - c.mean) * (t - c.mean) / (c.n - 1);
  c.std = std::sqrt(c.std);
  return c;
}

TEST(M3c2ReliefTest, BandMovedTenMillimetresReadsTenWhenDSpansTheCarving) {
  const relief::SynthOptions panel = PanelOptions();
  const ImageF height_m = relief::ReliefHeightField(panel, 0);
  const PointCloud before = Survey(height_m, panel.PixelM(), 0.0, 61);
  const PointCloud after = Survey(height_m, panel.PixelM(), kShift, 62);

  const DeviationResult r = RunM3c2(before, after, kNormalScale);
  EXPECT_EQ(r.undefined, 0u);
  const Region band = Summarise(r, after, true), still = Summarise(r, after, false);
  ASSERT_GT(band.n, 900u);
  ASSERT_GT(still.n, 4000u);
  EXPECT_LT(band.tilted_share, 0.05);  // the panel's normal, not the figures'
  EXPECT_NEAR(band.mean, kShift, 0.0005);
  EXPECT_NEAR(still.mean, 0.0, 0.0005);
  EXPECT_LE(still.significant_share, 0.05);  // a 95 % level: at most ~5 % by chance
  // The carving keeps LoD95 above 10 mm on much of the band, yet the change shows on a good part.
  EXPECT_GT(band.significant_share, 0.2);

  // D = 0.24 m, the figures' own scale (D / roughness ~14 on this panel): the normals follow
  // their flanks, and the band's move, read along them, comes out short.
  const Region small = Summarise(RunM3c2(before, after, 0.24), after, true);
  EXPECT_GT(small.tilted_share, 0.5);
  EXPECT_LT(small.mean, kShift - 0.0004);
}

TEST(M3c2ReliefTest, CarvingRaisesTheLevelOfDetection) {
  const relief::SynthOptions panel = PanelOptions();
  const ImageF carved = relief::ReliefHeightField(panel, 0);
  const ImageF flat(carved.width(), carved.height(), 1, 0.0f);
  const PointCloud before = Survey(carved, panel.PixelM(), 0.0, 71);
  const PointCloud again = Survey(carved, panel.PixelM(), 0.0, 72);
  const DeviationResult r = RunM3c2(before, again, kNormalScale);
  const DeviationResult f = RunM3c2(Survey(flat, panel.PixelM(), 0.0, 71),
                                    Survey(flat, panel.PixelM(), 0.0, 72), kNormalScale);
  // Flat: noise only, n ~ pi (d/2)^2 / spacing^2 points a side, LoD95 = 1.96 sqrt(2 / n) sigma.
  const double n = M_PI * std::pow(kProjectionScale / 2 / kSpacing, 2);
  EXPECT_NEAR(MedianLod(f), 1.96 * std::sqrt(2 / n) * kNoise,
              0.1 * 1.96 * std::sqrt(2 / n) * kNoise);
  // Carved: the carving within d is roughness at that scale, and it dominates the noise.
  EXPECT_GT(MedianLod(r), 10 * MedianLod(f));

  // A few core points, their cylinders recounted from the points along the normal used: the
  // counts, spreads, distance and LoD95 = 1.96 (sqrt(s1^2/n1 + s2^2/n2) + reg), reg = 0 here.
  for (size_t i = 0; i < again.size(); i += again.size() / 7) {
    ASSERT_FALSE(std::isnan(r.distance[i])) << i;
    const Eigen::Vector3d normal = r.normals[i].cast<double>().normalized();
    const Cylinder s1 = Recount(before, again.positions[i], normal);
    const Cylinder s2 = Recount(again, again.positions[i], normal);
    EXPECT_EQ(r.reference_count[i], s1.n) << i;
    EXPECT_EQ(r.compared_count[i], s2.n) << i;
    EXPECT_NEAR(r.reference_std[i], s1.std, 1e-7) << i;
    EXPECT_NEAR(r.compared_std[i], s2.std, 1e-7) << i;
    EXPECT_NEAR(r.distance[i], s2.mean - s1.mean, 1e-7) << i;
    const double lod = 1.96 * std::sqrt(s1.std * s1.std / s1.n + s2.std * s2.std / s2.n);
    EXPECT_NEAR(r.lod95[i], lod, 1e-6) << i;
  }
}

}  // namespace
}  // namespace candi::compare

// Opacity control for stochastic point-based rendering (SPBR; ALGORITHMS.md §1).
//
// The SPBR opacity law: a local surface of area S holding n points, rendered as L ensembles of
// points whose cross-section (one pixel's footprint in world units) has area s, has opacity
//
//     alpha = 1 - (1 - s/S)^(n/L)            and conversely   n/L = ln(1 - alpha) / ln(1 - s/S).
//
// Point-number adjustment (AdjustOpacity) makes every point's neighbourhood hold the number of
// points the target alpha needs: points of too-dense regions are removed at random, points of
// too-sparse regions are replicated, and each copy must go to a *distinct* ensemble (two copies
// in one ensemble occlude each other and add nothing), so a point has at most L copies.
// The copies are not materialised: the output carries a float scalar field "spbr_multiplicity"
// (kMultiplicityField) with each point's number of copies m_i >= 1, and the renderer puts the
// copies of a point into m_i distinct ensembles.
// Thread-safe (reentrant). Deterministic: the output depends on the options and the cloud only.
#pragma once

#include <cstdint>
#include <string>

#include "core/point_cloud.h"
#include "core/spbr_settings.h"
#include "sampling/density.h"

namespace candi::sampling {

// The scalar field holding a point's number of copies (PLY property "scalar_spbr_multiplicity").
inline constexpr char kMultiplicityField[] = "spbr_multiplicity";

// alpha = 1 - (1 - s/S)^(n/L), computed as -expm1((n/L) log1p(-s/S)) so that it keeps full
// precision when s/S is tiny (the naive form loses every digit below s/S ~ 1e-16 and most of them
// long before). points_per_ensemble = n/L >= 0 (+inf allowed); point_area_ratio = s/S >= 0.
// Edges: n/L = 0 or s/S = 0 gives 0; s/S >= 1 (one point covers the whole area; larger ratios are
// treated as 1) gives 1 for any n/L > 0; n/L = +inf gives 1 (when s/S > 0).
// Negative or NaN arguments are misuse: CANDI_CHECK.
double SpbrAlpha(double points_per_ensemble, double point_area_ratio);

// The inverse: n/L = log1p(-alpha) / log1p(-s/S), for alpha in [0, 1] and s/S >= 0.
// Edges: alpha = 0 gives 0 (no points, transparent); alpha = 1 gives +inf (no finite number of
// points is fully opaque; callers cap); s/S = 0 with alpha > 0 gives +inf. At s/S >= 1 the law
// has no useful inverse (any n/L > 0 gives alpha = 1, and n/L = 0 gives 0): the function returns
// its limit as s/S rises to 1, which is 0 for alpha < 1 and +inf for alpha = 1. AdjustOpacity
// never asks there (it keeps s/S <= kMaxPointAreaRatio). Bad arguments: CANDI_CHECK.
double SpbrPointsPerEnsemble(double alpha, double point_area_ratio);

// The largest s/S AdjustOpacity uses. The law assumes exactly n/L points in S; on a surface
// sampled uniformly the count in a small S varies (Poisson), and the coverage a renderer measures
// is 1 - exp(-rho s / L), the law's limit for S >> s. The two differ by a factor 1 + (s/S)/2 in
// the exponent: at s/S = 0.5 a target of 0.5 renders as 0.39, at 0.01 as 0.498. So when pixels
// are coarse, s > kMaxPointAreaRatio * pi r^2, S is enlarged to s / kMaxPointAreaRatio (the
// density measured within r taken as that of the larger S; the summary says so).
inline constexpr double kMaxPointAreaRatio = 0.01;

struct OpacityOptions {
  double alpha = 0.5;      // target opacity, [0, 1]
  // L (the ensembles the renderer averages; 1 when opaque) and the seed of the copy counts' random
  // rounding: the settings of the render the cloud is for (its point size is not used here).
  SpbrSettings spbr;
  // The pixel footprint's side s_side (s = s_side^2): exactly one of the two is > 0.
  double pixel_size = 0.0;  // m, >= 0; 0 = from image_size
  int image_size = 1024;    // N pixels across the cloud's largest bounding-box extent, >= 0:
                            // s_side = extent / N; 0 = use pixel_size
  // Local density. Its weight_field is ignored: AdjustOpacity sets it to kMultiplicityField when
  // the input has that field, so such a point counts as that many points (see AdjustOpacity).
  DensityOptions density;
  // Throws std::invalid_argument("OpacityOptions::field = value; rule") (or DensityOptions::...).
  void Check() const;
};

struct OpacitySummary {
  size_t points_in = 0;
  size_t points_out = 0;         // points with m_i >= 1
  uint64_t total_copies = 0;     // sum of m_i: the points the renderer draws
  double expected_copies = 0.0;  // sum of min(w_i r_i, L): the expectation of total_copies
  size_t removed = 0;            // m_i = 0
  size_t replicated = 0;         // m_i > 1
  size_t capped = 0;             // w_i r_i > L: the target is not reached around these points
  double ratio_min = 0.0, ratio_median = 0.0, ratio_max = 0.0;  // r_i = n'_i / n_i; may be +inf
  double pixel_size = 0.0;                                      // s_side used, m
  double radius = 0.0;                                          // density radius r, m
  double area = 0.0;              // S used, m^2: pi r^2, or s / kMaxPointAreaRatio if larger
  double point_area_ratio = 0.0;  // s / S used
  double median_density = 0.0;    // points per m^2 before adjustment (weighted)
  double points_needed = 0.0;     // n' = L * SpbrPointsPerEnsemble(alpha, s/S): points wanted in S
  // SpbrAlpha at the median density after adjustment: equals alpha unless the median point is
  // capped (then lower) or the cloud is empty (0).
  double predicted_alpha = 0.0;
  std::string message;  // notes for the user ("" when nothing to say)
};

struct OpacityResult {
  PointCloud cloud;  // the kept points, input order, all attributes, plus kMultiplicityField
  OpacitySummary summary;
};

// The point-number adjustment. For each point i (input index):
//   rho_i  = the local density (EstimateSurfaceDensity, options.density), S = pi r^2,
//   n_i    = rho_i S, n' = L * SpbrPointsPerEnsemble(alpha, s/S), r_i = n' / n_i,
//   m_i    = floor(w_i r_i) + (u_i < frac(w_i r_i)), capped at L,
// with w_i the input multiplicity (1 without the field) and u_i = ToUnit(HashIndex(seed, i, .))
// so that E[m_i] = w_i r_i (below the cap), independent of threads. A point with no neighbour
// (rho_i = 0) gets L copies (r_i = +inf); alpha = 0 removes every point.
// An input that already has kMultiplicityField (e.g. an adjusted cloud adjusted again) is
// treated as holding w_i copies of point i: the densities count them and the new m_i scales
// them, so re-adjusting with the same options keeps the copy count in expectation. Its values
// must be finite and >= 0 (InputError otherwise); the field keeps its type.
// An empty cloud gives an empty result. Failures: as EstimateSurfaceDensity.
OpacityResult AdjustOpacity(const OpacityOptions& options, const PointCloud& cloud);
// The same with the cloud's density already estimated (EstimateSurfaceDensity with
// options.density, the weight field set as AdjustOpacity sets it): the density does not depend on
// the view, so renders of one cloud from several views can share it. Same result, bit for bit.
// Throws std::invalid_argument when `density` does not have one value per point.
OpacityResult AdjustOpacity(const OpacityOptions& options, const PointCloud& cloud,
                            const DensityResult& density);
// The density AdjustOpacity(options, cloud) estimates.
DensityResult OpacityDensity(const OpacityOptions& options, const PointCloud& cloud);

}  // namespace candi::sampling

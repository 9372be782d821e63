#include "sampling/opacity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/check.h"
#include "core/rng.h"
#include "core/text_format.h"

namespace candi::sampling {

namespace {

constexpr uint64_t kCopyStream = 0x6f706163697479ULL;  // "opacity": the rounding draws u_i
constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Each point's input multiplicity w_i, or empty for "all 1".
std::vector<double> InputMultiplicity(const PointCloud& cloud) {
  const ScalarField* field = cloud.FindScalar(kMultiplicityField);
  if (field == nullptr) return {};
  std::vector<double> w(cloud.size());
  for (size_t i = 0; i < w.size(); ++i) w[i] = field->Get(i);  // validated by the density pass
  return w;
}

// The points-per-area ratio r_i = n' / (rho_i S), with the 0 / 0 and x / 0 cases spelled out.
double Ratio(double needed, double points_in_area) {
  if (needed == 0) return 0.0;
  if (!(points_in_area > 0)) return kInf;
  return needed / points_in_area;
}

// m_i: w_i r_i rounded up with probability equal to its fraction (so E[m_i] = w_i r_i), capped.
int Multiplicity(double copies, int cap, double u) {
  if (!(copies < cap)) return cap;  // also +inf
  const double whole = std::floor(copies);
  return static_cast<int>(whole) + (u < copies - whole ? 1 : 0);
}

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  auto mid = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

// The kept points (input order, every attribute), with the multiplicity field set.
PointCloud Gather(const PointCloud& in, const std::vector<int>& copies, size_t kept) {
  PointCloud out;
  out.frame = in.frame;
  out.meta = in.meta;
  out.SetSchema(in.schema);
  if (out.schema.ScalarIndex(kMultiplicityField) < 0) out.AddScalarField(kMultiplicityField);
  out.Resize(kept);
  ScalarField* field = out.FindScalar(kMultiplicityField);
  size_t j = 0;
  for (size_t i = 0; i < in.size(); ++i) {
    if (copies[i] == 0) continue;
    out.positions[j] = in.positions[i];
    if (in.schema.colors) out.colors[j] = in.colors[i];
    if (in.schema.alphas) out.alphas[j] = in.alphas[i];
    if (in.schema.normals) out.normals[j] = in.normals[i];
    if (in.schema.layers) out.layers[j] = in.layers[i];
    for (size_t f = 0; f < in.scalars.size(); ++f) out.scalars[f].Set(j, in.scalars[f].Get(i));
    field->Set(j, copies[i]);
    ++j;
  }
  return out;
}

// s_side from the options: given, or the largest bounding-box extent over image_size.
double PixelSide(const OpacityOptions& o, const PointCloud& cloud) {
  if (o.pixel_size > 0) return o.pixel_size;
  return cloud.LocalBounds().Extent().maxCoeff() / o.image_size;
}

void AddNote(OpacitySummary* s, const std::string& note) {
  s->message += (s->message.empty() ? "" : "; ") + note;
}

// Fills the scale fields of the summary: pixel, radius, S and s/S (with the coarse-pixel guard).
void SetScales(const OpacityOptions& o, const PointCloud& cloud, const DensityResult& density,
               OpacitySummary* s) {
  s->pixel_size = PixelSide(o, cloud);
  const double point_area = s->pixel_size * s->pixel_size;
  s->radius = density.radius;
  s->area = density.area;
  if (point_area > kMaxPointAreaRatio * s->area) {
    s->area = point_area / kMaxPointAreaRatio;
    AddNote(s, "pixels (" + FormatSignificant(s->pixel_size, 10) +
                   " m) are coarse for the density radius " + FormatSignificant(s->radius, 10) +
                   " m: S enlarged to " + FormatSignificant(s->area, 10) +
                   " m^2 so that s/S = " + FormatSignificant(kMaxPointAreaRatio, 10));
  }
  s->point_area_ratio = point_area / s->area;
  s->median_density = density.median_density;
  s->points_needed =
      o.spbr.EffectiveRepeatLevel() * SpbrPointsPerEnsemble(o.alpha, s->point_area_ratio);
}

// Ratio statistics, counts and the predicted alpha at the median density.
void Summarize(const OpacityOptions& o, std::vector<double> ratios, const std::vector<int>& copies,
               OpacitySummary* s) {
  s->ratio_median = Median(ratios);
  const auto [lo, hi] = std::minmax_element(ratios.begin(), ratios.end());
  s->ratio_min = *lo;
  s->ratio_max = *hi;
  for (int m : copies) {
    s->total_copies += m;
    s->removed += m == 0;
    s->replicated += m > 1;
  }
  s->points_out = s->points_in - s->removed;
  const double median_points = s->median_density * s->area;
  const double after = median_points * std::min(Ratio(s->points_needed, median_points),
                                                static_cast<double>(o.spbr.EffectiveRepeatLevel()));
  s->predicted_alpha = SpbrAlpha(after / o.spbr.EffectiveRepeatLevel(), s->point_area_ratio);
  if (o.alpha == 0) AddNote(s, "alpha = 0: every point removed");
  if (s->capped > 0) {
    AddNote(s, std::to_string(s->capped) + " points wanted more than repeat_level = " +
                   std::to_string(o.spbr.EffectiveRepeatLevel()) +
                   " copies and were capped: the target alpha is not reached there");
  }
}

}  // namespace

double SpbrAlpha(double points_per_ensemble, double point_area_ratio) {
  CANDI_CHECK(points_per_ensemble >= 0 && point_area_ratio >= 0)
      << "SpbrAlpha(" << points_per_ensemble << ", " << point_area_ratio << ")";
  const double x = std::min(point_area_ratio, 1.0);
  if (points_per_ensemble == 0 || x == 0) return 0.0;
  if (x == 1.0 || std::isinf(points_per_ensemble)) return 1.0;
  return -std::expm1(points_per_ensemble * std::log1p(-x));
}

double SpbrPointsPerEnsemble(double alpha, double point_area_ratio) {
  CANDI_CHECK(alpha >= 0 && alpha <= 1 && point_area_ratio >= 0)
      << "SpbrPointsPerEnsemble(" << alpha << ", " << point_area_ratio << ")";
  if (alpha == 0) return 0.0;
  if (alpha == 1) return kInf;
  if (point_area_ratio == 0) return kInf;
  if (point_area_ratio >= 1) return 0.0;
  return std::log1p(-alpha) / std::log1p(-point_area_ratio);
}

void OpacityOptions::Check() const {
  CANDI_CHECK_OPTION_IN(alpha, 0, 1);
  spbr.Check();
  CANDI_CHECK_OPTION(pixel_size >= 0 && std::isfinite(pixel_size), pixel_size,
                     "finite and >= 0 (0 = from image_size)");
  CANDI_CHECK_OPTION_GE(image_size, 0);
  CANDI_CHECK_OPTION_PAIR((pixel_size > 0) != (image_size > 0), pixel_size, image_size,
                          "exactly one must be > 0 (the other 0)");
  density.Check();
}

DensityResult OpacityDensity(const OpacityOptions& options, const PointCloud& cloud) {
  options.Check();
  DensityOptions density_options = options.density;
  density_options.weight_field = cloud.FindScalar(kMultiplicityField) ? kMultiplicityField : "";
  return EstimateSurfaceDensity(density_options, cloud);
}

OpacityResult AdjustOpacity(const OpacityOptions& options, const PointCloud& cloud) {
  if (cloud.empty()) return AdjustOpacity(options, cloud, DensityResult());
  return AdjustOpacity(options, cloud, OpacityDensity(options, cloud));
}

OpacityResult AdjustOpacity(const OpacityOptions& options, const PointCloud& cloud,
                            const DensityResult& density) {
  options.Check();
  OpacityResult result;
  OpacitySummary& s = result.summary;
  s.points_in = cloud.size();
  if (cloud.empty()) {
    result.cloud = Gather(cloud, {}, 0);
    AddNote(&s, "empty input");
    return result;
  }
  if (density.density.size() != cloud.size()) {
    throw std::invalid_argument("AdjustOpacity: " + std::to_string(density.density.size()) +
                                " density values for " + std::to_string(cloud.size()) + " points");
  }
  SetScales(options, cloud, density, &s);
  const std::vector<double> w = InputMultiplicity(cloud);
  std::vector<double> ratios(cloud.size());
  std::vector<int> copies(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    ratios[i] = Ratio(s.points_needed, density.density[i] * s.area);
    const double weight = w.empty() ? 1.0 : w[i];
    const double wanted = weight == 0 ? 0.0 : weight * ratios[i];  // 0 copies of a point stay 0
    const double u = ToUnit(HashIndex(options.spbr.seed, i, kCopyStream));
    copies[i] = Multiplicity(wanted, options.spbr.EffectiveRepeatLevel(), u);
    s.capped += wanted > options.spbr.EffectiveRepeatLevel();
    s.expected_copies += std::min(wanted, static_cast<double>(options.spbr.EffectiveRepeatLevel()));
  }
  Summarize(options, std::move(ratios), copies, &s);
  result.cloud = Gather(cloud, copies, s.points_out);
  return result;
}

}  // namespace candi::sampling

#include "core/field_colour.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>

#include "core/check.h"
#include "core/text_format.h"

namespace candi {

namespace {

// The value at quantile q of the finite values (at most kSample of them, evenly strided, so a
// range over 10^9 points costs a sort of 10^6).
double Quantile(const std::vector<const std::vector<double>*>& values, double q, bool absolute) {
  constexpr size_t kSample = size_t{1} << 20;
  size_t total = 0;
  for (const auto* v : values) total += v->size();
  const size_t stride = std::max<size_t>(1, total / kSample);
  std::vector<double> sample;
  size_t at = 0;
  for (const auto* v : values) {
    for (double x : *v) {
      if (at++ % stride != 0 || !std::isfinite(x)) continue;
      sample.push_back(absolute ? std::abs(x) : x);
    }
  }
  if (sample.empty()) return std::numeric_limits<double>::quiet_NaN();
  const size_t k = std::min(sample.size() - 1, static_cast<size_t>(q * static_cast<double>(sample.size() - 1) + 0.5));
  std::nth_element(sample.begin(), sample.begin() + k, sample.end());
  return sample[k];
}

}  // namespace

FieldScale ParseFieldScale(const std::string& text) {
  if (text == "auto") return FieldScale::kAuto;
  if (text == "diverging") return FieldScale::kDiverging;
  if (text == "sequential") return FieldScale::kSequential;
  if (text == "classes") return FieldScale::kClasses;
  throw std::invalid_argument("scale '" + text + "': expected auto, diverging, sequential or classes");
}

const char* FieldScaleName(FieldScale scale) {
  switch (scale) {
    case FieldScale::kAuto: return "auto";
    case FieldScale::kDiverging: return "diverging";
    case FieldScale::kSequential: return "sequential";
    case FieldScale::kClasses: return "classes";
  }
  return "?";
}

void FieldColouring::Check() const {
  if (std::isnan(lo) != std::isnan(hi)) throw std::invalid_argument("field range: give both ends, lo,hi");
  if (!std::isnan(lo) && !(std::isfinite(lo) && std::isfinite(hi) && lo < hi)) {
    throw std::invalid_argument("field range " + FormatDouble(lo) + "," + FormatDouble(hi) +
                                ": expected finite lo < hi");
  }
}

Rgb8 FieldLegend::Colour(double value) const {
  if (std::isnan(value)) return kOutOfRangeGrey;
  if (scale == FieldScale::kClasses) return ClassColour(static_cast<int>(std::lround(value)));
  if (value < lo || value > hi) return kOutOfRangeGrey;
  const double t = (value - lo) / (hi - lo);
  return scale == FieldScale::kDiverging ? DivergingColour(2 * t - 1) : SequentialColour(t);
}

std::vector<FieldLegend::ColourRun> FieldLegend::ColourRuns() const {
  std::vector<ColourRun> runs;
  if (scale == FieldScale::kClasses) return runs;
  // The values drawn in one colour form one run along the scale (its colours change
  // monotonically between stops): consecutive grid values of the same colour.
  for (int i = 0; i <= kColourSteps; ++i) {
    const Rgb8 c = Colour(lo + (hi - lo) * i / kColourSteps);
    if (!runs.empty() && runs.back().colour == c) {
      runs.back().last = i;
    } else {
      runs.push_back({c, i, i});
    }
  }
  return runs;
}

std::optional<double> FieldLegend::ValueOfColour(Rgb8 colour, double* half_width) const {
  *half_width = 0;
  if (colour == kOutOfRangeGrey) return std::nullopt;
  if (scale == FieldScale::kClasses) {
    for (int c : classes) {
      if (ClassColour(c) == colour) return c;
    }
    return std::nullopt;
  }
  const std::vector<ColourRun> runs = ColourRuns();
  const double step = (hi - lo) / kColourSteps;
  int first = -1, last = -1;
  for (const ColourRun& r : runs) {
    if (!(r.colour == colour)) continue;
    if (first < 0) first = r.first;
    last = r.last;
  }
  if (first >= 0) {
    // The colour's values reach past the samples that show it by less than a step either side.
    *half_width = 0.5 * (last - first + 2) * step;
    return lo + 0.5 * (first + last) * step;
  }
  // A colour the samples skip: where two channels change within one step of the samples, the
  // colour between the two changes is drawn only inside that step. It lies channel by channel
  // between the runs on either side of the step.
  auto between = [](uint8_t c, uint8_t a, uint8_t b) { return (a <= c && c <= b) || (b <= c && c <= a); };
  for (size_t k = 0; k + 1 < runs.size(); ++k) {
    const Rgb8 a = runs[k].colour, b = runs[k + 1].colour;
    if (between(colour.r, a.r, b.r) && between(colour.g, a.g, b.g) && between(colour.b, a.b, b.b)) {
      *half_width = 0.5 * step;
      return lo + (runs[k].last + 0.5) * step;
    }
  }
  return std::nullopt;
}

std::vector<double> FieldValues(const PointCloud& cloud, const std::string& field, const std::string& name) {
  std::vector<double> values(cloud.size());
  if (const ScalarField* f = cloud.FindScalar(field)) {
    for (size_t i = 0; i < values.size(); ++i) values[i] = f->Get(i);
    return values;
  }
  if (field == "elevation") {
    for (size_t i = 0; i < values.size(); ++i) values[i] = cloud.positions[i].z() + cloud.frame.origin.z();
    return values;
  }
  std::string have;
  for (const ScalarFieldSpec& s : cloud.schema.scalars) have += (have.empty() ? "" : ", ") + s.name;
  throw InputError(name, "", "no scalar field '" + field + "' to colour by (it has " +
                                 (have.empty() ? std::string("none") : have) + "; elevation is always there)");
}

FieldLegend ResolveFieldColouring(const FieldColouring& c, const std::vector<const std::vector<double>*>& values) {
  c.Check();
  CANDI_CHECK(c.active());
  FieldLegend legend;
  legend.field = c.field;
  legend.scale = c.scale;
  if (legend.scale == FieldScale::kAuto) {
    bool negative = false, positive = false;
    for (const auto* v : values) {
      for (double x : *v) {
        negative |= x < 0;
        positive |= x > 0;
      }
    }
    // An elevation is a level, not a deviation: sequential even where it crosses zero.
    const bool level = c.field == "elevation";
    legend.scale = c.field == "classification"                              ? FieldScale::kClasses
                   : c.field == "distance" || (negative && positive && !level) ? FieldScale::kDiverging
                                                                                 : FieldScale::kSequential;
  }
  if (legend.scale == FieldScale::kClasses) {
    std::set<int> present;
    for (const auto* v : values) {
      for (double x : *v) {
        if (std::isfinite(x)) present.insert(static_cast<int>(std::lround(x)));
      }
    }
    legend.classes.assign(present.begin(), present.end());
    legend.lo = legend.classes.empty() ? 0 : legend.classes.front();
    legend.hi = legend.classes.empty() ? 0 : legend.classes.back();
  } else if (!std::isnan(c.lo)) {
    legend.lo = c.lo;
    legend.hi = c.hi;
  } else if (legend.scale == FieldScale::kDiverging) {
    double m = Quantile(values, 0.98, /*absolute=*/true);
    if (!(m > 0)) m = 1;  // no finite value, or all zero: a unit range
    legend.lo = -m;
    legend.hi = m;
  } else {
    legend.lo = Quantile(values, 0.02, false);
    legend.hi = Quantile(values, 0.98, false);
    if (std::isnan(legend.lo)) {
      legend.lo = 0;
      legend.hi = 1;
    } else if (!(legend.hi > legend.lo)) {  // one value: a range about it
      const double pad = std::max(1e-9, std::abs(legend.lo) * 1e-6);
      legend.lo -= pad;
      legend.hi += pad;
    }
  }
  for (const auto* v : values) {
    for (double x : *v) {
      ++legend.count;
      if (std::isnan(x)) {
        ++legend.undefined;
      } else if (legend.scale != FieldScale::kClasses && (x < legend.lo || x > legend.hi)) {
        ++legend.outside;
      }
    }
  }
  return legend;
}

void ColourByField(const FieldLegend& legend, const std::vector<double>& values, PointCloud* cloud) {
  CANDI_CHECK(values.size() == cloud->size()) << values.size() << " values for " << cloud->size() << " points";
  if (!cloud->schema.colors) {
    PointSchema schema = cloud->schema;
    schema.colors = true;
    cloud->SetSchema(schema);
  }
  for (size_t i = 0; i < values.size(); ++i) cloud->colors[i] = legend.Colour(values[i]);
}

Rgb8 ClassColour(int c) {
  // ASPRS LAS 1.4 standard classes, in the colours viewers commonly give them.
  static constexpr Rgb8 kStandard[] = {
      {180, 180, 180},  // 0 created, never classified
      {210, 210, 210},  // 1 unclassified
      {166, 118, 64},   // 2 ground
      {170, 225, 120},  // 3 low vegetation
      {90, 185, 80},    // 4 medium vegetation
      {25, 120, 40},    // 5 high vegetation
      {225, 75, 60},    // 6 building
      {255, 0, 255},    // 7 low point (noise)
      {255, 230, 0},    // 8 reserved (model key point)
      {60, 120, 230},   // 9 water
      {150, 90, 160},   // 10 rail
      {90, 90, 90},     // 11 road surface
      {255, 200, 0},    // 12 reserved (overlap)
      {250, 160, 200},  // 13 wire guard
      {240, 110, 170},  // 14 wire conductor
      {120, 60, 20},    // 15 transmission tower
      {200, 120, 240},  // 16 wire connector
      {200, 170, 120},  // 17 bridge deck
      {255, 0, 128},    // 18 high noise
  };
  if (c >= 0 && c < 19) return kStandard[c];
  // Beyond the standard ones: a fixed, well spread hue per class.
  const double h = std::fmod(static_cast<double>(static_cast<uint32_t>(c)) * 0.618033988749895, 1.0);
  const double r = 0.5 + 0.4 * std::cos(6.283185307179586 * h);
  const double g = 0.5 + 0.4 * std::cos(6.283185307179586 * (h - 1.0 / 3));
  const double b = 0.5 + 0.4 * std::cos(6.283185307179586 * (h - 2.0 / 3));
  return {static_cast<uint8_t>(std::lround(255 * r)), static_cast<uint8_t>(std::lround(255 * g)),
          static_cast<uint8_t>(std::lround(255 * b))};
}

std::string ClassName(int c) {
  static const char* kNames[] = {"never classified", "unclassified", "ground", "low vegetation",
                                 "medium vegetation", "high vegetation", "building", "low noise",
                                 "model key point", "water", "rail", "road surface", "overlap",
                                 "wire guard", "wire conductor", "tower", "wire connector",
                                 "bridge deck", "high noise"};
  if (c >= 0 && c < 19) return kNames[c];
  return "class " + std::to_string(c);
}

}  // namespace candi

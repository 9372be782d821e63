// Colouring points by a scalar field: a deviation on a diverging scale, an elevation or an
// intensity on a sequential one, LAS classes by the ASPRS palette. The range is given or taken
// from the values (robust percentiles); values outside it and undefined ones (NaN) are grey and
// counted, so a picture never hides them. The resolved colouring (FieldLegend) is what a legend
// draws and what the values' colours are computed from.
// The field "elevation" is the points' world z where a cloud has no scalar field of that name.
// Failures: std::invalid_argument for a bad range or scale, InputError (naming the cloud and the
// fields it has) for a field it lacks.
#pragma once

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/colour_map.h"
#include "core/point_cloud.h"

namespace candi {

enum class FieldScale { kAuto, kDiverging, kSequential, kClasses };

// "auto", "diverging", "sequential", "classes"; std::invalid_argument otherwise.
FieldScale ParseFieldScale(const std::string& text);
const char* FieldScaleName(FieldScale scale);

struct FieldColouring {
  std::string field;  // empty: no colouring by a field
  // kAuto: classes for "classification"; diverging for a field holding both signs or named
  // "distance"; else sequential.
  FieldScale scale = FieldScale::kAuto;
  // The range; NaN: from the values (diverging: +-the 98th percentile of |v|, symmetric about 0;
  // sequential: the 2nd to the 98th percentile). Classes ignore it.
  double lo = std::numeric_limits<double>::quiet_NaN();
  double hi = std::numeric_limits<double>::quiet_NaN();
  bool active() const { return !field.empty(); }
  void Check() const;  // lo < hi when both are given; a range needs both or neither
};

// A colouring resolved against the values: what the colours come from and a legend states.
struct FieldLegend {
  std::string field;
  FieldScale scale = FieldScale::kSequential;  // never kAuto
  double lo = 0, hi = 1;
  std::vector<int> classes;                    // kClasses: the classes present, ascending
  uint64_t count = 0, outside = 0, undefined = 0;  // points, outside [lo, hi] (grey), NaN (grey)
  Rgb8 Colour(double value) const;
  // What a colour on this scale stands for (a point stored with its colour, as in a render
  // archive): the middle of the values drawn in exactly that colour, and in *half_width how far
  // they reach either side (8-bit colours: about (hi - lo) / 1000). Classes: the class code, 0.
  // None for the grey (outside the range, or undefined) or a colour not on the scale.
  std::optional<double> ValueOfColour(Rgb8 colour, double* half_width) const;
  // The scale sampled at kColourSteps + 1 even values lo + (hi - lo) * i / kColourSteps: runs of
  // consecutive samples drawn in one colour, in value order (what ValueOfColour reads; a page
  // decodes a picked colour from them). Empty for classes.
  static constexpr int kColourSteps = 1 << 14;
  struct ColourRun {
    Rgb8 colour;
    int first, last;  // sample indices, inclusive
  };
  std::vector<ColourRun> ColourRuns() const;
};

// The field's values of `cloud` in point order (double; world z for "elevation"). `name` names
// the cloud in the error for a missing field.
std::vector<double> FieldValues(const PointCloud& cloud, const std::string& field, const std::string& name);

// Resolves `colouring` over the values of every cloud drawn together (one legend for all).
FieldLegend ResolveFieldColouring(const FieldColouring& colouring, const std::vector<const std::vector<double>*>& values);

// Sets the cloud's colours from its field values (values.size() == cloud->size()).
void ColourByField(const FieldLegend& legend, const std::vector<double>& values, PointCloud* cloud);

// The colour of a LAS class (ASPRS standard classes 0-18; others a fixed colour per class).
Rgb8 ClassColour(int class_code);
// Its name ("ground", "building", ...; "class 42" beyond the standard ones).
std::string ClassName(int class_code);

}  // namespace candi

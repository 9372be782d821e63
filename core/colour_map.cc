#include "core/colour_map.h"

#include <cmath>

namespace candi {

namespace {

// Linear interpolation at t in [0, 1] between `count` evenly spaced stops.
Rgb8 Interpolate(const Rgb8* stops, int count, double t) {
  if (std::isnan(t)) return kOutOfRangeGrey;
  t = t < 0 ? 0 : (t > 1 ? 1 : t);
  const double x = t * (count - 1);
  int i = static_cast<int>(x);
  if (i >= count - 1) i = count - 2;
  const double f = x - i;
  auto mix = [&](uint8_t a, uint8_t b) {
    return static_cast<uint8_t>(std::lround(a + (static_cast<double>(b) - a) * f));
  };
  return {mix(stops[i].r, stops[i + 1].r), mix(stops[i].g, stops[i + 1].g),
          mix(stops[i].b, stops[i + 1].b)};
}

}  // namespace

Rgb8 DivergingColour(double t) {
  static constexpr Rgb8 kStops[] = {{5, 48, 97},    {33, 102, 172}, {67, 147, 195},
                                    {146, 197, 222}, {247, 247, 247}, {244, 165, 130},
                                    {214, 96, 77},  {178, 24, 43},  {103, 0, 31}};
  return Interpolate(kStops, 9, 0.5 * (t + 1));
}

Rgb8 SequentialColour(double t) {
  static constexpr Rgb8 kStops[] = {{68, 1, 84},    {59, 82, 139}, {33, 145, 140},
                                    {94, 201, 98}, {253, 231, 37}};
  return Interpolate(kStops, 5, t);
}

}  // namespace candi

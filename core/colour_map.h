// Colour scales for scalar fields (deviation maps, histograms, legends): a diverging scale for
// signed values (blue, white at zero, red; after ColorBrewer's RdBu, colour-blind safe) and a
// sequential one for magnitudes (viridis-like). Both interpolate linearly in sRGB between a few
// stops; inputs outside the range are clamped, NaN gives grey.
#pragma once

#include "core/point_cloud.h"

namespace candi {

// t in [-1, 1]: -1 blue, 0 white, +1 red.
Rgb8 DivergingColour(double t);
// t in [0, 1]: dark purple to yellow.
Rgb8 SequentialColour(double t);
// The grey of values outside a clamped range or undefined.
inline constexpr Rgb8 kOutOfRangeGrey{150, 150, 150};

}  // namespace candi

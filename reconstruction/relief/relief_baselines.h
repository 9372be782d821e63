// Classical single-image baselines for relief depth, scored beside the network.
//
// Both return a *relative* height (arbitrary scale and offset, larger = nearer the viewer);
// FitLevels maps it to depth levels with the least-squares scale and offset against the ground
// truth (an oracle an absolute network does not get: the most favourable reading of each
// baseline; relative networks are scored with the same fit).
//  - intensity as depth: the grey value itself is the height (brighter = nearer);
//  - linear shape from shading (Pentland 1988, "Shape information from shading: a theory about
//    human perception", via the FFT): with reflectance linearised in the surface gradient,
//    I - mean = n.L = -lx z_x + ly z_y (y up), so F(I) = i (ly w_y - lx w_x) F(z); z is the
//    regularised inverse (frequencies across the light direction are unrecoverable and damped).
// Thread-safe.
#pragma once

#include "core/image.h"

namespace candi::relief {

// Relative height = grey value.
ImageF IntensityAsHeight(const ImageF& photo);

// Pentland's linear shape from shading. light_azimuth_deg in the panel frame (0 = from the right,
// 90 = from above); light_elevation_deg above the wall plane, in (0, 90).
ImageF PentlandHeight(const ImageF& photo, double light_azimuth_deg, double light_elevation_deg);

// Levels = clamp(255 - (a * relative + b)), a and b minimising the squared level error over the
// valid ground-truth pixels (>= kMinValidLevel). Without valid pixels: a constant mid level.
ImageF FitLevels(const ImageF& relative_height, const ImageF& ground_truth_levels);

}  // namespace candi::relief

// Synthetic scenes for measuring SPBR: translucent layers and a terraced solid, generated with a
// seed. Used by the accuracy sweep (`candi bench render`), the benchmarks and the tests.
#pragma once

#include <cstdint>

#include "core/point_cloud.h"
#include "render/camera.h"

namespace candi::render {

// n points uniformly on the rectangle [0, sx] x [0, sy] at height z, in one colour.
PointCloud UniformRectangle(uint64_t n, double sx, double sy, double z, Rgb8 color, uint64_t seed);

// n points on `layers` stacked, coloured, partly overlapping square sheets (side 100 m, 10 m
// apart, each tilted a little), with random positions: a see-through test scene whose exact
// blended image is known from RenderSortedBlend.
PointCloud LayeredSheets(uint64_t n, int layers, uint64_t seed);

// n points on a stepped, temple-like solid (square terraces, a dome), coloured by height: the
// shape of the bundled example at any size, for throughput measurements.
PointCloud TerracedSolid(uint64_t n, uint64_t seed);

// An oblique view that frames `cloud` (in the render frame of `cloud`'s bounds).
Camera ObliqueView(const Box3d& bounds_in_render_frame, int width, int height);

}  // namespace candi::render

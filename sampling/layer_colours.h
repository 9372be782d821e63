// Display colours of foundation layers, as in the paper's Table 1: A blue (andesite), B yellow
// (foam with andesite), C red (soft volcanic tuff), D green (andesite with stone chips). Other
// layer names take colours from a fixed palette by their index. Thread-safe.
#pragma once

#include <cstddef>
#include <string>

#include "core/point_cloud.h"

namespace candi::sampling {

struct LayerColour {
  Rgb8 rgb;
  std::string name;  // "blue", "yellow", ...
};

LayerColour DefaultLayerColour(const std::string& layer, size_t index);

}  // namespace candi::sampling

#include "sampling/layer_colours.h"

namespace candi::sampling {

LayerColour DefaultLayerColour(const std::string& layer, size_t index) {
  if (layer == "A") return {{40, 90, 230}, "blue"};
  if (layer == "B") return {{240, 210, 40}, "yellow"};
  if (layer == "C") return {{220, 40, 40}, "red"};
  if (layer == "D") return {{40, 170, 70}, "green"};
  static const LayerColour kPalette[] = {{{0, 190, 200}, "cyan"},    {{200, 60, 200}, "magenta"},
                                         {{245, 140, 30}, "orange"}, {{130, 80, 200}, "purple"},
                                         {{150, 150, 150}, "grey"},  {{140, 90, 50}, "brown"}};
  return kPalette[index % (sizeof(kPalette) / sizeof(kPalette[0]))];
}

}  // namespace candi::sampling

// The size of a relief panel where none is given: the Karmawibhangga panels of Borobudur's hidden
// foot, 2.7 m wide and 0.92 m high, carved up to 0.15 m deep. Every relief default (synthetic
// panels, depth to points, the network's resolution, a scene's relief layer) takes it from here.
#pragma once

namespace candi::relief {

inline constexpr double kPanelWidthM = 2.7;
inline constexpr double kPanelHeightM = 0.92;
inline constexpr double kPanelDepthM = 0.15;

}  // namespace candi::relief

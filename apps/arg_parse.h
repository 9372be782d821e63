// Parsing of option values shared by the commands ("1,2,3", "1024x768").
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

#include "core/clip.h"

namespace candi::app {

// Finite numbers separated by `separator`; throws std::invalid_argument("<what> '<text>': ...").
std::vector<double> ParseNumbers(const std::string& text, char separator, const std::string& what);
// "x,y,z", a non-zero finite direction (std::invalid_argument naming `what` otherwise).
Eigen::Vector3d ParseDirection(const std::string& text, const std::string& what);

// --clip-box "xmin,ymin,zmin,xmax,ymax,zmax" (world coordinates, min <= max on every axis; empty:
// none) and --clip-plane "px,py,pz,nx,ny,nz" (each keeps the side its normal points into) as one
// region; std::invalid_argument naming the option and the text.
ClipRegion ParseClip(const std::string& box, const std::vector<std::string>& planes);
// The part of `world` the region's box planes keep (the other planes are not applied): what a
// default view frames.
Box3d ClippedBounds(const Box3d& world, const ClipRegion& region);

}  // namespace candi::app

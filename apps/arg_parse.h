// Parsing of option values shared by the commands ("1,2,3", "1024x768").
#pragma once

#include <Eigen/Core>

#include <string>
#include <vector>

#include "core/clip.h"
#include "core/point_cloud.h"
#include "core/text_format.h"

namespace candi::apps {

// "x,y,z", a non-zero finite direction (std::invalid_argument naming `what` otherwise).
Eigen::Vector3d ParseDirection(const std::string& text, const std::string& what);

// "WxH", whole pixels in [1, 16384] each (std::invalid_argument naming `what` otherwise).
void ParseSize(const std::string& text, const std::string& what, int* width, int* height);
// "r,g,b", each a whole number in [0, 255] (std::invalid_argument naming `what` otherwise).
Rgb8 ParseColour(const std::string& text, const std::string& what);

// --clip-box "xmin,ymin,zmin,xmax,ymax,zmax" (world coordinates, min <= max on every axis; empty:
// none) and --clip-plane "px,py,pz,nx,ny,nz" (each keeps the side its normal points into) as one
// region; std::invalid_argument naming the option and the text.
ClipRegion ParseClip(const std::string& box, const std::vector<std::string>& planes);

}  // namespace candi::apps

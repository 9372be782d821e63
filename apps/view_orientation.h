// The orientation of a default view (`candi render` without --view, `candi view`'s first view)
// from the command line: --up, --from, or --cameras (a COLMAP model whose frame the points are in).
#pragma once

#include <string>

#include "view/source.h"

namespace candi::app {

// Cameras: up is the mean of the cameras' image-up directions (-y of each camera, in the model's
// frame), the view looks the mean way the cameras look. --up and --from override them. Throws
// std::invalid_argument naming the option for bad values, InputError for an unreadable model.
view::Orientation ParseOrientation(const std::string& up, const std::string& from, const std::string& cameras);

}  // namespace candi::app

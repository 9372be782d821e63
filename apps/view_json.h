// Views as JSON, so a render can be repeated exactly: the camera in world coordinates (metres),
// {"projection": "perspective"|"orthographic", "width": 1024, "height": 768,
//  "eye": [x, y, z], "target": [x, y, z], "up": [0, 0, 1], "fov_y_deg": 40,
//  "ortho_height": 10, "near": 0.001}. Missing fields keep Camera's defaults; unknown keys and
// bad values fail with InputError naming the file and the JSON path of the culprit.
#pragma once

#include <string>

#include "render/camera.h"

namespace candi::app {

render::Camera LoadView(const std::string& path);
std::string ViewToJson(const render::Camera& world_camera);
void SaveView(const std::string& path, const render::Camera& world_camera);

}  // namespace candi::app

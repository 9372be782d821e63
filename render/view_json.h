// Views as JSON, so a render can be repeated exactly: the camera in world coordinates (metres),
// {"projection": "perspective"|"orthographic", "width": 1024, "height": 768,
//  "eye": [x, y, z], "target": [x, y, z], "up": [0, 0, 1], "fov_y_deg": 40,
//  "ortho_height": 10, "near": 0.001}. Missing fields keep Camera's defaults; unknown keys and
// bad values fail with InputError naming `name` (the file, or the message it came in) and the
// JSON path of the culprit. The format of `candi render --view/--save-view`, of scene views and
// of the viewer's "save this view".
#pragma once

#include <string>

#include "render/camera.h"

namespace candi::render {

Camera ParseView(const std::string& text, const std::string& name);
std::string ViewToJson(const Camera& world_camera);

// A view file: read (InputError naming it), and written atomically (with a final newline).
Camera LoadView(const std::string& path);
void SaveView(const std::string& path, const Camera& world_camera);

}  // namespace candi::render

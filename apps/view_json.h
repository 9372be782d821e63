// View files (render/view_json.h's format): read and written atomically.
#pragma once

#include <string>

#include "render/camera.h"
#include "render/view_json.h"

namespace candi::app {

render::Camera LoadView(const std::string& path);
using render::ViewToJson;
void SaveView(const std::string& path, const render::Camera& world_camera);

}  // namespace candi::app

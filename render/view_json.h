// Views as JSON, so a render can be repeated exactly: the camera in world coordinates (metres),
// {"projection": "perspective"|"orthographic", "width": 1024, "height": 768,
//  "eye": [x, y, z], "target": [x, y, z], "up": [0, 0, 1], "fov_y_deg": 40,
//  "ortho_height": 10, "near": 0.001}. Missing fields keep Camera's defaults; unknown keys and
// bad values fail with InputError naming `name` (the file, or the message it came in) and the
// JSON path of the culprit. The format of `candi render --view/--save-view`, of scene views and
// of the viewer's "save this view".
// A page's saved or shared view (candi view, candi publish) adds "settings": {"layers": [shares],
// "layer_names": [names], "clip": [[px, py, pz, nx, ny, nz], ...] (world), and "repeat_level",
// "seed", "opaque", "point_size", "background", "brightness"}; ParseView returns the layers'
// shares and the clipping in `settings` (candi render applies them; the others are the page's
// and are given to candi render as flags).
#pragma once

#include <string>
#include <vector>

#include "core/clip.h"
#include "render/camera.h"

namespace candi::render {

struct SavedViewSettings {
  std::vector<std::string> layer_names;  // with layer_shares: each layer's share of its points
  std::vector<double> layer_shares;      // each in [0, 16]
  ClipRegion clip;                       // world
};

Camera ParseView(const std::string& text, const std::string& name, SavedViewSettings* settings = nullptr);
std::string ViewToJson(const Camera& world_camera);

// A view file: read (InputError naming it), and written atomically (with a final newline).
Camera LoadView(const std::string& path, SavedViewSettings* settings = nullptr);
void SaveView(const std::string& path, const Camera& world_camera);

}  // namespace candi::render

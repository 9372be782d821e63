// A synthetic scene's views written as a COLMAP dense workspace (synthetic_workspace.h).
#include "reconstruction/photogrammetry/scenes/synthetic_workspace.h"

#include <cmath>
#include <filesystem>
#include <string>

namespace candi::photogrammetry {

namespace fs = std::filesystem;

ColmapModel ToColmapModel(const std::vector<SyntheticView>& views,
                          const std::vector<Eigen::Vector3d>& points) {
  ColmapModel model;
  for (size_t k = 0; k < views.size(); ++k) {
    const PinholeCamera& c = views[k].camera;
    const uint32_t id = static_cast<uint32_t>(k + 1);
    model.cameras[id] = ColmapCamera{id, "PINHOLE", c.width, c.height, {c.fx, c.fy, c.cx, c.cy}};
    ColmapImage image;
    image.image_id = id;
    image.camera_id = id;
    image.name = views[k].name;
    image.cam_from_world_rotation = Eigen::Quaterniond(c.rotation);
    image.cam_from_world_translation = c.translation;
    model.images[id] = image;
  }
  for (size_t i = 0; i < points.size(); ++i) {
    ColmapPoint3d p;
    p.point3d_id = i + 1;
    p.xyz = points[i];
    p.rgb = {128, 128, 128};
    // Seen by the views where it is the visible surface: in the image, at the true depth (1 %).
    for (size_t k = 0; k < views.size() && p.xyz.allFinite(); ++k) {
      const PinholeCamera& c = views[k].camera;
      const Eigen::Vector3d x = c.ToCamera(p.xyz);
      if (!(x.z() > 0)) continue;
      const Eigen::Vector2d uv = c.Project(x);
      if (!(uv.x() >= 0 && uv.y() >= 0 && uv.x() < c.width && uv.y() < c.height)) continue;
      const double truth = views[k].depth.at(static_cast<int>(uv.x()), static_cast<int>(uv.y()));
      if (!(truth > 0) || std::abs(truth - x.z()) > 0.01 * x.z()) continue;
      ColmapImage& image = model.images[static_cast<uint32_t>(k + 1)];
      p.track.push_back({image.image_id, static_cast<uint32_t>(image.points2d.size())});
      image.points2d.push_back(uv);
      image.point3d_ids.push_back(p.point3d_id);
    }
    model.points3d[p.point3d_id] = p;
  }
  return model;
}

void WriteDenseWorkspace(const std::vector<SyntheticView>& views,
                         const std::vector<Eigen::Vector3d>& points, const std::string& workspace) {
  WriteSyntheticImages(views, (fs::path(workspace) / "images").string());
  const std::string sparse = (fs::path(workspace) / "sparse").string();
  fs::create_directories(sparse);
  WriteColmapModelBinary(ToColmapModel(views, points), sparse);
  fs::create_directories(fs::path(workspace) / "stereo" / "depth_maps");
  fs::create_directories(fs::path(workspace) / "stereo" / "normal_maps");
}

}  // namespace candi::photogrammetry

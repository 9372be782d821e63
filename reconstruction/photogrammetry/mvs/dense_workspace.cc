// The file half of dense_workspace.h (uses colmap_model.h's readers and writers).
#include "reconstruction/photogrammetry/mvs/dense_workspace.h"

#include <algorithm>
#include <filesystem>
#include <string>

#include "core/check.h"
#include "io/image/jpeg_io.h"

namespace candi::photogrammetry {

namespace fs = std::filesystem;

StereoInput ReadDenseWorkspace(const std::string& workspace) {
  const std::string sparse = (fs::path(workspace) / "sparse").string();
  const ColmapModel model = ReadColmapModel(sparse);
  if (model.images.empty()) throw InputError(sparse, "", "the model has no images");
  StereoInput in;
  for (const auto& [id, image] : model.images) {
    const auto camera = model.cameras.find(image.camera_id);
    if (camera == model.cameras.end())
      throw InputError(sparse, "image " + std::to_string(id),
                       "camera " + std::to_string(image.camera_id) + " is not in the model");
    StereoImage s;
    s.name = image.name;
    s.camera = ToPinholeCamera(camera->second, image, sparse);
    const std::string path = (fs::path(workspace) / "images" / image.name).string();
    s.image = io::ReadImageRgb8(path);
    if (s.image.width() != s.camera.width || s.image.height() != s.camera.height)
      throw InputError(path, "", "image is " + std::to_string(s.image.width()) + "x" +
                                     std::to_string(s.image.height()) + ", its camera " +
                                     std::to_string(s.camera.width) + "x" +
                                     std::to_string(s.camera.height));
    in.images.push_back(std::move(s));
  }
  for (const auto& [id, point] : model.points3d)
    if (point.xyz.allFinite()) in.sparse_points.push_back(point.xyz);
  return in;
}

void WriteDepthNormalMaps(const std::vector<DepthNormalMap>& maps,
                          const std::vector<std::string>& names, const std::string& workspace) {
  CANDI_CHECK(maps.size() == names.size()) << maps.size() << " maps, " << names.size() << " names";
  const fs::path stereo = fs::path(workspace) / "stereo";
  for (size_t k = 0; k < maps.size(); ++k) {
    const fs::path depth = stereo / "depth_maps" / (names[k] + ".geometric.bin");
    const fs::path normal = stereo / "normal_maps" / (names[k] + ".geometric.bin");
    fs::create_directories(depth.parent_path());  // names may hold sub-folders
    fs::create_directories(normal.parent_path());
    WriteColmapArray(DepthArray(maps[k]), depth.string());
    WriteColmapArray(NormalArray(maps[k]), normal.string());
  }
}

}  // namespace candi::photogrammetry

#include "reconstruction/photogrammetry/georef/georef_colmap.h"

#include <cmath>

#include "core/check.h"
#include "reconstruction/photogrammetry/sfm/colmap_model.h"

namespace candi::photogrammetry {

namespace {

Eigen::Matrix3d Intrinsics(const ColmapCamera& c, const std::string& dir) {
  const std::vector<double>& p = c.params;
  size_t distortion_from = 0;
  Eigen::Matrix3d k = Eigen::Matrix3d::Identity();
  if ((c.model == "SIMPLE_PINHOLE" || c.model == "SIMPLE_RADIAL" || c.model == "RADIAL") &&
      p.size() >= 3) {
    k << p[0], 0, p[1], 0, p[0], p[2], 0, 0, 1;
    distortion_from = 3;
  } else if ((c.model == "PINHOLE" || c.model == "OPENCV" || c.model == "FULL_OPENCV") &&
             p.size() >= 4) {
    k << p[0], 0, p[2], 0, p[1], p[3], 0, 0, 1;
    distortion_from = 4;
  } else {
    throw InputError(dir, "camera " + std::to_string(c.camera_id),
                     "camera model " + c.model + " is not supported for picking");
  }
  for (size_t i = distortion_from; i < p.size(); ++i) {
    if (p[i] != 0) {
      throw InputError(dir, "camera " + std::to_string(c.camera_id),
                       c.model + " with lens distortion: pick in the undistorted images and give "
                       "their model (COLMAP image_undistorter's sparse folder)");
    }
  }
  return k;
}

}  // namespace

ColmapGeorefInput ReadColmapForGeoref(const std::string& sparse_dir) {
  const ColmapModel model = ReadColmapModel(sparse_dir);
  ColmapGeorefInput in;
  for (const auto& [id, image] : model.images) {
    const auto camera = model.cameras.find(image.camera_id);
    if (camera == model.cameras.end()) {
      throw InputError(sparse_dir, "image " + std::to_string(id), "unknown camera " +
                                                                   std::to_string(image.camera_id));
    }
    ProjectionMatrix rt;
    rt << image.cam_from_world_rotation.toRotationMatrix(), image.cam_from_world_translation;
    in.cameras[image.name] = Intrinsics(camera->second, sparse_dir) * rt;
  }
  PointSchema schema;
  schema.colors = true;
  in.points.SetSchema(schema);
  for (const auto& [id, point] : model.points3d) {
    in.points.positions.push_back(point.xyz);
    in.points.colors.push_back(Rgb8{point.rgb[0], point.rgb[1], point.rgb[2]});
  }
  return in;
}

void WriteGeoreferencedColmapModel(const std::string& sparse_dir, const Sim3& local_from_model,
                                   const std::string& out_dir) {
  ColmapModel model = ReadColmapModel(sparse_dir);
  for (auto& [id, point] : model.points3d) point.xyz = local_from_model * point.xyz;
  // x_cam = R X + t with X = T^-1 Y; scaling the camera frame by s keeps every projection:
  // R' = R Rs^T, t' = s t - R' ts (Rs, ts, s: the similarity).
  const Eigen::Quaterniond rs = local_from_model.rotation;
  for (auto& [id, image] : model.images) {
    const Eigen::Quaterniond r = image.cam_from_world_rotation * rs.conjugate();
    image.cam_from_world_translation =
        local_from_model.scale * image.cam_from_world_translation - r * local_from_model.translation;
    image.cam_from_world_rotation = r.normalized();
  }
  WriteColmapModelBinary(model, out_dir);
}

}  // namespace candi::photogrammetry

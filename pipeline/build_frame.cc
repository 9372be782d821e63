#include <Eigen/Core>
#include <algorithm>
#include <unordered_map>
#include <unordered_set>

#include "core/check.h"
#include "core/log.h"
#include "io/crs.h"
#include "pipeline/build_internal.h"

namespace candi::pipeline::internal {

using nlohmann::json;

// Drops the points of `target` that `by` covers: their voxel (edge `voxel`, on the scene frame's
// local grid) holds >= 3 points of `by`, and a point of `by` lies in their fine cell (edge
// voxel / 8) or one of the 26 around it. The second test keeps a few stray points of `by` from
// cutting a hole in a surface of `target` they do not cover (the demo's close range had stray
// points on the encasement, and hidden panels showed through the holes). Close-range data
// supersedes a coarse scan where it has data. Both clouds are in the scene's frame. Returns the
// number of points dropped.
size_t ReplaceWhereCovered(const PointCloud& by, double voxel, PointCloud* target) {
  using Cell = Eigen::Array<int64_t, 3, 1>;
  auto cell = [](const Eigen::Vector3d& p, double size) -> Cell {
    // Clamped to +-2^20 cells (a 0.5 m voxel's fine cells cover +-65 km).
    return (p / size).array().floor().max(-1048576.0).min(1048575.0).cast<int64_t>();
  };
  auto key = [](const Cell& c) {  // 21 bits per axis
    auto axis = [](int64_t v) { return static_cast<uint64_t>(v + 1048576) & 0x1fffff; };
    return axis(c.x()) << 42 | axis(c.y()) << 21 | axis(c.z());
  };
  const double fine = voxel / 8;
  std::unordered_map<uint64_t, uint32_t> counts;
  std::unordered_set<uint64_t> occupied;
  for (const Eigen::Vector3d& p : by.positions) {
    if (!p.allFinite()) continue;
    ++counts[key(cell(p, voxel))];
    occupied.insert(key(cell(p, fine)));
  }
  auto near_by = [&](const Eigen::Vector3d& p) {
    const Cell c = cell(p, fine);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz)
          if (occupied.count(key(c + Cell(dx, dy, dz)))) return true;
    return false;
  };
  std::vector<uint8_t> keep(target->size(), 1);
  for (size_t i = 0; i < target->size(); ++i) {
    const auto it = counts.find(key(cell(target->positions[i], voxel)));
    keep[i] = it == counts.end() || it->second < 3 || !near_by(target->positions[i]);
  }
  return target->Keep(keep);
}

// The layer's coordinates into the scene's CRS (scene.h, "crs"): a layer stating another CRS is
// transformed with PROJ; one stating none is taken to be in the scene's, with a warning. Points
// outside the target CRS's domain become NaN (dropped and counted by Place). Returns what
// archive.json records of the layer's CRS.
json ToSceneCrs(const Scene& scene, size_t k, PointCloud* cloud) {
  const SceneLayer& l = scene.layers[k];
  const std::string at = "/layers/" + std::to_string(k) + "/crs";
  std::string stated = cloud->meta.crs;
  if (l.crs == "scene") {
    if (!stated.empty() && !io::SameCrs(stated, scene.crs))
      throw InputError(scene.path, at, "layer " + l.name + " says \"scene\" (" + io::CrsLabel(scene.crs) +
                                           ") but its data states " + io::CrsLabel(stated));
    stated = scene.crs;
  } else if (!l.crs.empty()) {
    if (!stated.empty() && !io::SameCrs(stated, l.crs))
      throw InputError(scene.path, at, "layer " + l.name + " declares " + io::CrsLabel(l.crs) +
                                           " but its data states " + io::CrsLabel(stated) + "; remove one");
    stated = l.crs;
  }
  json record = {{"stated", stated.empty() ? json() : json(io::CrsLabel(stated))}, {"transformed", false}};
  if (stated.empty()) {
    if (!scene.crs.empty())
      LogWarning("layer " + l.name + " states no CRS; taken to be in the scene's, " + io::CrsLabel(scene.crs) +
                 " (say so with \"crs\": \"scene\" in the layer)");
    cloud->meta.crs = scene.crs;
    return record;
  }
  cloud->meta.crs = stated;
  if (scene.crs.empty() || io::SameCrs(stated, scene.crs)) return record;
  const io::CrsTransform transform(stated, scene.crs, scene.path);
  for (Eigen::Vector3d& p : cloud->positions) p = cloud->frame.ToWorld(p);
  cloud->frame = LocalFrame();
  const size_t outside = transform.Apply(&cloud->positions);
  cloud->meta.crs = scene.crs;
  LogInfo("layer " + l.name + ": " + io::CrsLabel(stated) + " -> " + io::CrsLabel(scene.crs) + " with PROJ (" +
          transform.operation() + ")");
  if (outside > 0) LogWarning("layer " + l.name + ": " + std::to_string(outside) + " points lie outside " + io::CrsLabel(scene.crs));
  record["transformed"] = true;
  record["to"] = io::CrsLabel(scene.crs);
  record["operation"] = transform.operation();
  record["accuracy_m"] = transform.accuracy();
  record["outside_domain"] = outside;
  return record;
}

// Without a scene CRS, every layer that states one must state the same: the scene's CRS then.
std::string CommonCrs(const Scene& scene, const std::vector<PointCloud*>& clouds) {
  if (!scene.crs.empty()) return scene.crs;
  std::string common;
  size_t first = 0;
  for (size_t k = 0; k < clouds.size(); ++k) {
    const std::string& c = clouds[k]->meta.crs;
    if (c.empty()) continue;
    if (common.empty()) {
      common = c, first = k;
    } else if (!io::SameCrs(common, c)) {
      throw InputError(scene.path, "/crs", "layers " + scene.layers[first].name + " (" + io::CrsLabel(common) + ") and " +
                                               scene.layers[k].name + " (" + io::CrsLabel(c) +
                                               ") are in different CRSs; declare the scene's \"crs\" to transform "
                                               "them into one with PROJ");
    }
  }
  return common;
}

// world_from_layer, the colour override, the scene's frame; NaN positions are dropped (counted).
size_t Place(const SceneLayer& l, uint16_t id, const LocalFrame& scene_frame, PointCloud* cloud) {
  PointCloud& c = *cloud;
  std::vector<uint8_t> finite(c.size(), 1);
  for (size_t i = 0; i < c.size(); ++i) {
    const Eigen::Vector3d world = l.world_from_layer * c.frame.ToWorld(c.positions[i]);
    finite[i] = world.allFinite();
    if (!finite[i]) continue;
    c.positions[i] = scene_frame.ToLocal(world);
    if (c.schema.normals) {
      const Eigen::Vector3d n = l.world_from_layer.rotation * c.normals[i].cast<double>();
      c.normals[i] = n.cast<float>();
    }
  }
  const size_t dropped = c.Keep(finite);
  c.frame = scene_frame;
  PointSchema schema = c.schema;
  schema.colors = true;
  schema.scalars.clear();
  schema.scalars.push_back({"scene_layer", ScalarType::kFloat32});
  schema.scalars.push_back({"quality", ScalarType::kFloat32});
  const bool had_colors = c.schema.colors;
  c.SetSchema(schema);
  for (size_t i = 0; i < c.size(); ++i) {
    if (l.color || !had_colors) c.colors[i] = l.color ? *l.color : Rgb8{180, 180, 180};
    c.scalars[0].Set(i, id);
    c.scalars[1].Set(i, id);
  }
  return dropped;
}

}  // namespace candi::pipeline::internal

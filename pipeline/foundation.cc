#include "pipeline/foundation.h"

#include <limits>

#include "core/check.h"
#include "core/log.h"
#include "core/timer.h"
#include "mesh/dxf_import.h"
#include "sampling/layer_colours.h"

namespace candi::pipeline {

void FoundationPointsOptions::Check() const {
  surface.Check();
  sample.Check();
}

std::vector<std::string> FoundationPoints::Names() const {
  std::vector<std::string> names;
  for (const mesh::LayerSurface& s : surfaces) names.push_back(s.layer);
  return names;
}

PointCloud FoundationPoints::Merged() const {
  CANDI_CHECK(!clouds.empty());
  PointCloud merged;
  merged.SetSchema(clouds.front().schema);
  merged.frame = clouds.front().frame;
  std::string comment = "candi_layers";
  for (size_t k = 0; k < clouds.size(); ++k) {
    merged.Append(clouds[k]);
    comment += " " + std::to_string(k) + "=" + surfaces[k].layer;
  }
  merged.meta = PointCloudMeta();
  merged.meta.comments.push_back(comment);
  return merged;
}

FoundationPoints DigitizeFoundation(const FoundationPointsOptions& options, const std::string& dxf) {
  options.Check();
  Stopwatch watch;
  const mesh::DxfDrawing drawing = mesh::ReadDxf(options.surface.dxf, dxf);
  const std::vector<std::string> names = options.layers.empty() ? drawing.LayerNames() : options.layers;
  if (names.empty()) {
    throw InputError(dxf, "", "no layer holds a section (LWPOLYLINE, POLYLINE, LINE or SPLINE in model space)");
  }
  FoundationPoints out;
  out.unit_name = drawing.unit_name;
  out.drawing_layers = drawing.layers.size();
  out.surfaces = mesh::BuildLayerSurfaces(options.surface, drawing, names, options.sample.threads);
  for (const mesh::LayerSurface& layer : out.surfaces) {
    out.areas.push_back(sampling::MeshArea(layer.mesh));
    LogInfo("layer " + layer.layer + ": " + mesh::RevolveModeName(layer.mode) + ", " +
            std::to_string(layer.mesh.faces.size()) + " triangles");
  }
  out.mesh_seconds = watch.Lap();
  std::vector<uint64_t> counts;
  if (options.sample.count > 0) counts = sampling::SplitCount(options.sample.count, out.areas);
  for (size_t k = 0; k < out.surfaces.size(); ++k) {
    sampling::SurfaceSampleOptions o = options.sample;
    if (!counts.empty()) o.count = counts[k];
    if (!counts.empty() && counts[k] == 0) {  // rounds to no points: an empty cloud, same schema
      o.density = std::numeric_limits<double>::min();
    }
    o.colour = sampling::DefaultLayerColour(out.surfaces[k].layer, k).rgb;
    o.layer = static_cast<int>(k);
    out.clouds.push_back(sampling::SampleSurface(o, out.surfaces[k].mesh));
  }
  out.sample_seconds = watch.Lap();
  return out;
}

}  // namespace candi::pipeline

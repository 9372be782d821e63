#include "mesh/foundation.h"

#include <algorithm>
#include <atomic>
#include <exception>
#include <thread>

#include "core/check.h"

namespace candi::mesh {

void FoundationOptions::Check() const {
  dxf.Check();
  section.Check();
  profile.Check();
  revolve.Check();
  mesh.Check();
  check_options.Check();
}

Polyline2 LayerSection(const FoundationOptions& options, const DxfDrawing& drawing,
                       const std::string& layer) {
  const auto it = drawing.layers.find(layer);
  if (it == drawing.layers.end()) {
    std::string names;
    for (const std::string& name : drawing.LayerNames())
      names += (names.empty() ? "" : ", ") + name;
    throw InputError(drawing.path, "layer '" + layer + "'",
                     "no such layer with section geometry (the drawing has: " +
                         (names.empty() ? std::string("none") : names) + ")");
  }
  return AssembleSection(options.section, it->second, {drawing.path, layer});
}

LayerSurface BuildLayerSurface(const FoundationOptions& options, const DxfDrawing& drawing,
                               const std::string& layer) {
  options.Check();
  LayerSurface out;
  out.layer = layer;
  const Polyline2 section = LayerSection(options, drawing, layer);
  out.profile = BuildProfile(options.profile, section, {drawing.path, layer});
  const SurfaceGrid grid = RevolveProfile(options.revolve, out.profile);
  out.mode = grid.mode;
  out.asymmetry = grid.asymmetry;
  out.mesh = BuildSurfaceMesh(options.mesh, grid);
  if (options.check) {
    out.checked = true;
    out.check = CheckMesh(options.check_options, out.mesh);
  }
  return out;
}

std::vector<LayerSurface> BuildLayerSurfaces(const FoundationOptions& options,
                                             const DxfDrawing& drawing,
                                             const std::vector<std::string>& layers, int threads) {
  options.Check();
  std::vector<LayerSurface> out(layers.size());
  std::vector<std::exception_ptr> errors(layers.size());
  std::atomic<size_t> next{0};
  auto work = [&] {
    for (size_t k; (k = next++) < layers.size();) {
      try {
        out[k] = BuildLayerSurface(options, drawing, layers[k]);
      } catch (...) {
        errors[k] = std::current_exception();
      }
    }
  };
  const size_t hardware = std::max(1u, std::thread::hardware_concurrency());
  const size_t count =
      std::min(layers.size(), threads > 0 ? static_cast<size_t>(threads) : hardware);
  std::vector<std::thread> pool;
  for (size_t t = 1; t < count; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  return out;
}

}  // namespace candi::mesh

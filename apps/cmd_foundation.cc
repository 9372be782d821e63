// candi foundation DRAWING -o OUT: the unreachable foundation from CAD sections (mesh/foundation.h,
// sampling/surface_sampling.h). Builds each layer's surface, checks it, samples it uniformly and
// writes the points (merged with a layer field, or one file per layer) and optionally the meshes;
// prints a table like the paper's Table 1.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "core/check.h"
#include "core/log.h"
#include "io/point_io.h"
#include "mesh/foundation.h"
#include "mesh/mesh_export.h"
#include "sampling/layer_clouds.h"
#include "sampling/layer_colours.h"
#include "sampling/surface_sampling.h"

namespace candi::app {

namespace {

constexpr double kDefaultDensity = 50.0;  // points per m^2: the example at the paper's scale

mesh::FoundationOptions Options(const FoundationArgs& a) {
  mesh::FoundationOptions o;
  o.dxf.chord_tolerance = a.chord_tolerance;
  o.section.join_tolerance = a.join_tolerance;
  o.profile.samples_per_side = a.samples_per_side;
  o.revolve.mode = mesh::ParseRevolveMode(a.mode);
  o.revolve.angular_steps = a.angular_steps;
  if (!a.axis_x.empty()) o.revolve.axis_x = ParseNumbers(a.axis_x, ',', "--axis-x").at(0);
  o.revolve.symmetry_tolerance = a.symmetry_tolerance;
  o.mesh.close_base = a.close_base;
  o.check = !a.no_check;
  o.check_options.self_intersections = !a.no_self_intersection;
  o.Check();
  return o;
}

sampling::SurfaceSampleOptions SampleOptions(const FoundationArgs& a) {
  sampling::SurfaceSampleOptions s;
  if (a.per_triangle > 0) {
    s.mode = sampling::SurfaceSamplingMode::kPerTriangle;
    s.per_triangle = a.per_triangle;
  } else if (a.count > 0) {
    s.count = a.count;
  } else {
    s.density = a.density != 0 ? a.density : kDefaultDensity;  // a negative one fails Check
  }
  s.seed = a.seed;
  s.threads = a.threads;
  s.Check();
  return s;
}

// "<stem>_<layer><ext>" beside `path`.
std::string LayerPath(const std::string& path, const std::string& layer) {
  const std::filesystem::path p(path);
  return (p.parent_path() / (p.stem().string() + "_" + layer + p.extension().string())).string();
}

std::string Symmetric(const mesh::LayerSurface& s) {
  return s.mode == mesh::RevolveMode::kSweep ? "yes" : "no";
}

void PrintTable(const std::vector<mesh::LayerSurface>& layers, const std::vector<PointCloud>& clouds,
                const std::vector<double>& areas, const mesh::RevolveOptions& revolve) {
  std::printf("%-8s %-8s %10s %-9s %-6s %10s %12s %10s  %s\n", "layer", "colour", "points",
              "symmetric", "mode", "asymmetry", "area m^2", "triangles", "mesh check");
  size_t total = 0;
  for (size_t k = 0; k < layers.size(); ++k) {
    const mesh::LayerSurface& s = layers[k];
    total += clouds[k].size();
    std::printf("%-8s %-8s %10zu %-9s %-6s %10.2e %12.1f %10zu  %s\n", s.layer.c_str(),
                sampling::DefaultLayerColour(s.layer, k).name.c_str(), clouds[k].size(), Symmetric(s).c_str(),
                mesh::RevolveModeName(s.mode).c_str(), s.asymmetry, areas[k], s.mesh.faces.size(),
                s.checked ? s.check.Summary().c_str() : "not checked");
  }
  std::printf("%-8s %-8s %10zu\n", "total", "", total);
  if (revolve.mode == mesh::RevolveMode::kAuto) {
    std::printf(
        "mode auto: layers whose sides mirror within %.3g of their extent are swept, the "
        "others blended\n",
        revolve.symmetry_tolerance);
  }
}

void WriteOutputs(const FoundationArgs& a, const std::vector<mesh::LayerSurface>& layers,
                  const std::vector<PointCloud>& clouds) {
  for (size_t k = 0; k < layers.size(); ++k) {
    if (!a.mesh.empty()) {
      mesh::WriteMesh(layers.size() == 1 ? a.mesh : LayerPath(a.mesh, layers[k].layer), layers[k].mesh);
    }
    if (a.split) io::WritePointCloud(LayerPath(a.output, layers[k].layer), clouds[k]);
  }
  if (!a.split) {  // one file with a layer field, streamed layer by layer (no merged copy)
    std::vector<std::string> names;
    for (const mesh::LayerSurface& layer : layers) names.push_back(layer.layer);
    sampling::WriteLayerClouds(a.output, clouds, names);
  }
}

double Seconds(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

}  // namespace

int RunFoundation(const FoundationArgs& args) {
  const mesh::FoundationOptions options = Options(args);  // bad values: std::invalid_argument, exit 1
  const sampling::SurfaceSampleOptions sample = SampleOptions(args);
  io::OutputPointFormat(args.output);  // a known extension, before the work
  const auto start = std::chrono::steady_clock::now();
  const mesh::DxfDrawing drawing = mesh::ReadDxf(options.dxf, args.input);
  const std::vector<std::string> names = args.layers.empty() ? drawing.LayerNames() : args.layers;
  if (names.empty()) {
    throw InputError(args.input, "",
                     "no layer holds a section (LWPOLYLINE, POLYLINE, LINE or "
                     "SPLINE in model space)");
  }
  const std::vector<mesh::LayerSurface> layers =
      mesh::BuildLayerSurfaces(options, drawing, names, args.threads);
  std::vector<double> areas;
  for (const mesh::LayerSurface& layer : layers) {
    areas.push_back(sampling::MeshArea(layer.mesh));
    LogInfo("layer " + layer.layer + ": " + mesh::RevolveModeName(layer.mode) + ", " +
            std::to_string(layer.mesh.faces.size()) + " triangles");
  }
  const double mesh_s = Seconds(start);
  std::vector<uint64_t> counts;
  if (sample.count > 0) counts = sampling::SplitCount(sample.count, areas);
  std::vector<PointCloud> clouds;
  for (size_t k = 0; k < layers.size(); ++k) {
    sampling::SurfaceSampleOptions o = sample;
    if (!counts.empty()) o.count = counts[k];
    if (!counts.empty() && counts[k] == 0) {  // rounds to no points: an empty cloud, same schema
      o.density = std::numeric_limits<double>::min();
    }
    o.colour = sampling::DefaultLayerColour(layers[k].layer, k).rgb;
    o.layer = static_cast<int>(k);
    clouds.push_back(sampling::SampleSurface(o, layers[k].mesh));
  }
  const double sample_s = Seconds(start) - mesh_s;
  WriteOutputs(args, layers, clouds);
  std::printf("drawing %s: %s, %zu layer(s) with sections, units %s\n", args.input.c_str(),
              args.split ? "points per layer" : "merged points", drawing.layers.size(),
              drawing.unit_name.c_str());
  PrintTable(layers, clouds, areas, options.revolve);
  std::printf("time: %.2f s (meshes and checks %.2f s, sampling %.2f s, writing %.2f s)\n",
              Seconds(start), mesh_s, sample_s, Seconds(start) - mesh_s - sample_s);
  return kOk;
}

}  // namespace candi::app

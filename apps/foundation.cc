// candi foundation: the foundation from a CAD section drawing (pipeline/foundation.h): profiles,
// Hermite resampling, rotational blending or sweep, mesh, uniform points.
#include <cstdio>
#include <filesystem>
#include <string>

#include "apps/commands.h"
#include "core/text_format.h"
#include "core/timer.h"
#include "io/layer_clouds.h"
#include "io/point_io.h"
#include "io/mesh_io.h"
#include "pipeline/foundation.h"
#include "sampling/layer_colours.h"

namespace candi::apps {

namespace {

namespace fs = std::filesystem;

struct FoundationArgs {
  std::string input;   // the section drawing (ASCII DXF)
  std::string output;  // point file; merged unless split
  pipeline::FoundationPointsOptions options;
  std::string mesh;    // optional mesh output (.obj .off .ply); per layer if several
  bool split = false;  // one point file per layer, <stem>_<layer><ext>
  std::string axis_x;  // drawing x of the axis, m; "" = through the reference point
};

// "<stem>_<layer><ext>" beside `path`.
std::string LayerPath(const std::string& path, const std::string& layer) {
  const fs::path p(path);
  return (p.parent_path() / (p.stem().string() + "_" + layer + p.extension().string())).string();
}

void PrintFoundation(const pipeline::FoundationPoints& f, const mesh::RevolveOptions& revolve) {
  std::printf("%-8s %-8s %10s %-9s %-6s %10s %12s %10s  %s\n", "layer", "colour", "points", "symmetric", "mode",
              "asymmetry", "area m^2", "triangles", "mesh check");
  size_t total = 0;
  for (size_t k = 0; k < f.surfaces.size(); ++k) {
    const mesh::LayerSurface& s = f.surfaces[k];
    total += f.clouds[k].size();
    std::printf("%-8s %-8s %10zu %-9s %-6s %10.2e %12.1f %10zu  %s\n", s.layer.c_str(),
                sampling::DefaultLayerColour(s.layer, k).name.c_str(), f.clouds[k].size(),
                s.mode == mesh::RevolveMode::kSweep ? "yes" : "no", mesh::RevolveModeName(s.mode).c_str(), s.asymmetry,
                f.areas[k], s.mesh.faces.size(), s.checked ? s.check.Summary().c_str() : "not checked");
  }
  std::printf("%-8s %-8s %10zu\n", "total", "", total);
  if (revolve.mode == mesh::RevolveMode::kAuto) {
    std::printf("mode auto: layers whose sides mirror within %.3g of their extent are swept, the others blended\n",
                revolve.symmetry_tolerance);
  }
}

int RunFoundation(const FoundationArgs& a) {
  pipeline::FoundationPointsOptions o = a.options;
  if (!a.axis_x.empty()) o.surface.revolve.axis_x = ParseNumbers(a.axis_x, ',', "--axis-x").at(0);
  if (o.sample.per_triangle > 0) {
    o.sample.mode = sampling::SurfaceSamplingMode::kPerTriangle;
  } else if (o.sample.count == 0 && o.sample.density == 0) {
    o.sample.density = pipeline::kDefaultFoundationDensity;  // a negative one fails Check
  }
  o.Check();  // bad values: std::invalid_argument, exit 1
  io::OutputPointFormat(a.output);  // a known extension, before the work
  const Stopwatch watch;
  const pipeline::FoundationPoints f = pipeline::DigitizeFoundation(o, a.input);
  for (size_t k = 0; k < f.surfaces.size(); ++k) {
    if (!a.mesh.empty()) {
      io::WriteMesh(f.surfaces.size() == 1 ? a.mesh : LayerPath(a.mesh, f.surfaces[k].layer), f.surfaces[k].mesh);
    }
    if (a.split) io::WritePointCloud(LayerPath(a.output, f.surfaces[k].layer), f.clouds[k]);
  }
  if (!a.split) io::WriteLayerClouds(a.output, f.clouds, f.Names());  // one file with a layer field
  std::printf("drawing %s: %s, %zu layer(s) with sections, units %s\n", a.input.c_str(),
              a.split ? "points per layer" : "merged points", f.drawing_layers, f.unit_name.c_str());
  PrintFoundation(f, o.surface.revolve);
  const double total = watch.Seconds();
  std::printf("time: %.2f s (meshes and checks %.2f s, sampling %.2f s, writing %.2f s)\n", total, f.mesh_seconds,
              f.sample_seconds, total - f.mesh_seconds - f.sample_seconds);
  return kOk;
}

}  // namespace

void AddFoundation(Command& root) {
  FoundationArgs& a = root.Keep<FoundationArgs>();
  mesh::FoundationOptions& s = a.options.surface;
  sampling::SurfaceSampleOptions& sample = a.options.sample;
  Command c = root.Add("foundation", "Foundation layers from a CAD section drawing (DXF): profiles, Hermite "
                                     "resampling, rotational blending or sweep, mesh, uniform points");
  c.Option("drawing", a.input, "Section drawing (ASCII DXF)").Required();
  c.Option("-o,--output", a.output, "Point file " CANDI_POINT_FILES_WRITTEN ": merged with a layer field, or one per layer "
           "with --split").Required();
  c.Option("--layers", a.options.layers, "Layers to build, e.g. A,B,C,D (default: all with a section)").Delimiter(',');
  c.Option("--samples-per-side", s.profile.samples_per_side, "N: Hermite samples per side (>= 2)");
  c.Option("--angular-steps", s.revolve.angular_steps, "M: steps per half-turn (>= 2)");
  Arg count = c.Option("--count", sample.count, "Total points, split over the layers by area");
  Arg density = c.Option("--density", sample.density, "Points per m^2 (default 50)");
  Arg per = c.Option("--per-triangle", sample.per_triangle, "The paper's mode: this many points in every triangle "
                     "(not uniform; for comparison)");
  count.Excludes(density);
  per.Excludes(count).Excludes(density);
  c.Choice("--mode", s.revolve.mode,
           {{"auto", mesh::RevolveMode::kAuto}, {"blend", mesh::RevolveMode::kBlend},
            {"sweep", mesh::RevolveMode::kSweep}},
           "auto (sweep symmetric layers, blend the others), blend or sweep");
  c.Option("--mesh", a.mesh, "Also write the mesh (.obj .off .ply); <stem>_<layer><ext> when several layers");
  c.Flag("--split", a.split, "One point file per layer: <stem>_<layer><ext>");
  c.Flag("--close-base", s.mesh.close_base, "Close each mesh's bottom ring (a solid)");
  c.FlagOff("--no-check", s.check, "Skip the CGAL mesh checks");
  c.FlagOff("--no-self-intersection", s.check_options.self_intersections,
            "Skip only CGAL's self-intersection test (the slowest check)");
  c.Option("--axis-x", a.axis_x, "Drawing x of the vertical axis, m (default: through each layer's highest point)");
  c.Option("--symmetry-tolerance", s.revolve.symmetry_tolerance, "auto: sides mirrored within this fraction of the "
           "section's extent count as symmetric");
  c.Option("--chord-tolerance", s.dxf.chord_tolerance, "Bulge arcs: largest chord error, m");
  c.Option("--join-tolerance", s.section.join_tolerance, "LINE ends closer than this join, m");
  c.Option("--seed", sample.seed, "Random seed of the sampling");
  c.Option("--threads", sample.threads, "Threads (0: all)").Range(0, 256);
  c.Run([&a] { return RunFoundation(a); });
  c.Footer("Example: candi foundation examples/borobudur/foundation.dxf -o foundation.ply --layers A,B,C,D --mesh "
           "foundation.obj");
}

}  // namespace candi::apps

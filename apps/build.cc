// candi build, candi demo: the integrated archive of a scene file (pipeline/build.h), and the
// bundled example's site built (pipeline/demo_site.h; RunDemo in demo.cc, candi-relief only).
#include <cmath>
#include <cstdio>
#include <string>

#include "apps/commands.h"
#include "apps/option_groups.h"
#include "core/text_format.h"
#include "pipeline/build.h"
#include "pipeline/scene.h"

namespace candi::apps {

namespace {

struct BuildArgs {
  std::string scene;  // scene JSON (pipeline/scene.h)
  pipeline::BuildOptions options;
  double copc_memory_mb = 0;
};

int RunBuild(const BuildArgs& a) {
  pipeline::BuildOptions o = a.options;
  o.copc_memory_bytes = CopcMemoryBytes(a.copc_memory_mb);
  const pipeline::Scene scene = pipeline::LoadScene(a.scene);
  PrintBuildSummary(o.output, pipeline::Build(o, scene));
  return kOk;
}

}  // namespace

void PrintBuildSummary(const std::string& output, const pipeline::BuildSummary& s) {
  std::printf("%-16s %-15s %12s %8s %-8s %s\n", "layer", "kind", "points", "opacity", "scanned", "seconds");
  for (const pipeline::BuildLayerSummary& l : s.layers) {
    std::printf("%-16s %-15s %12llu %8.3g %-8s %.1f\n", l.name.c_str(), pipeline::LayerKindName(l.kind).c_str(),
                static_cast<unsigned long long>(l.points), l.opacity, l.scanned ? "yes" : "no", l.seconds);
  }
  for (const pipeline::BuildComparisonSummary& c : s.comparisons) {
    auto mm = [](double m) { return std::isnan(m) ? std::string("n/a") : FormatSignificant(m * 1000, 4) + " mm"; };
    const std::string within =
        std::isnan(c.within_tolerance) ? "n/a" : FormatSignificant(100 * c.within_tolerance, 4) + " %";
    std::printf("comparison %s (%s, %llu points): mean %s, rms %s, %s within %s%s\n", c.name.c_str(),
                c.method.c_str(), static_cast<unsigned long long>(c.count), mm(c.mean).c_str(), mm(c.rms).c_str(),
                within.c_str(), mm(c.tolerance).c_str(), c.resumed ? " (resumed)" : "");
  }
  std::printf("%s: %llu points in %zu layers, frame origin %s, %zu render(s), %.1f s\n", output.c_str(),
              static_cast<unsigned long long>(s.points), s.layers.size(), s.frame.ToString().c_str(), s.views,
              s.seconds);
}

void AddBuild(Command& root) {
  BuildArgs& a = root.Keep<BuildArgs>();
  Command c = root.Add("build", "Build the integrated archive of a scene file: every layer digitized, placed in one "
                                "frame, written per layer, packed, rendered, with provenance (archive.json) and a "
                                "MeshLab project");
  c.Option("scene", a.scene, "Scene JSON (format: pipeline/scene.h, README)").Required();
  c.Option("-o,--output", a.options.output, "Archive folder").Required();
  c.Option("--threads", a.options.threads, "Threads (0: all)").Range(0, 256);
  c.Flag("--resume", a.options.resume, "Reuse what an earlier build into the same folder finished (its digitized "
         "layers, archive and renders) where their inputs are unchanged");
  AddCopcMemory(c, a.copc_memory_mb);
  c.Run([&a] { return RunBuild(a); });
  c.Footer("Example: candi build examples/borobudur/scene.json -o borobudur_archive");
}

void AddDemo(Command& root) {
  DemoArgs& a = root.Keep<DemoArgs>();
  pipeline::DemoSiteOptions& o = a.site;
  Command c = root.Add("demo", "Build and render the bundled example");
  c.Option("-o,--output", a.output_dir, "Output folder");
  c.Option("--width", o.width, "Image width in pixels").Range(16, 16384);
  c.Option("--height", o.height, "Image height in pixels").Range(16, 16384);
  c.Option("--seed", o.seed, "Random seed");
  Arg quick = c.Flag("--quick", o.quick, "The reduced scene (fewer points, L = 32), as CI runs it");
  c.Flag("--full", o.full, "Paper scale: all 160 relief panels through the network at the model's resolution "
         "(default: the 156 hidden ones at their photos' own, 8x fewer tiles)").Excludes(quick);
  c.Run([&a] { return RunDemo(a); });
  c.Footer("Example: candi demo -o demo_out");
}

}  // namespace candi::apps

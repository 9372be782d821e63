// candi build, candi pack, candi export, candi demo: the integrated archive of a scene file
// (pipeline/build.h), point files packed into a render archive (render/archive_pack.h), a finished
// build's layers as COPC (pipeline/copc_export.h), and the bundled example's site built
// (pipeline/demo_site.h; RunDemo in demo_command.cc, candi-relief only).
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>

#include "apps/commands.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "pipeline/build.h"
#include "pipeline/copc_export.h"
#include "pipeline/scene.h"
#include "render/archive_pack.h"

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

namespace {

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

struct PackArgs {
  std::vector<std::string> inputs;
  std::string output;        // archive directory
  render::PackOptions options;
  double memory_mb = 400;    // sort buffers (~100 bytes a point)
  std::string columns;       // XYZ/PTS inputs
  FieldArgs field;           // the points coloured by a scalar field
};

int RunPack(const PackArgs& a) {
  if (!(a.memory_mb > 0)) throw std::invalid_argument("--memory must be > 0 MB");
  render::PackOptions o = a.options;
  o.memory_points = std::max<uint64_t>(o.chunk_points, static_cast<uint64_t>(a.memory_mb * 1048576.0 / 100));
  ConsoleProgress progress("pack");
  const FieldColouring colour_by = ParseFieldColouring(a.field);
  const render::PackSummary s =
      render::PackFiles(o, a.inputs, a.columns, a.output, progress.Callback(), colour_by);
  progress.Finish();
  std::printf("%s: %llu points in %llu chunks, %llu data file(s), %.2f bytes/point, %.1f s (%.1f M points/s: "
              "bounds %.1f s, sort and write %.1f s; input hashes %.1f s on another thread meanwhile)%s, %zu-byte records; "
              "largest quantization error %.3g, %.3g, %.3g mm\n",
              a.output.c_str(), static_cast<unsigned long long>(s.points), static_cast<unsigned long long>(s.chunks),
              static_cast<unsigned long long>(s.files), s.points ? static_cast<double>(s.bytes) / s.points : 0.0,
              s.seconds, s.points / s.seconds / 1e6, s.bounds_seconds, s.sort_seconds, s.hash_seconds,
              s.spilled_points ? ", sorted on disk" : "", s.record_bytes, 1e3 * s.max_error[0], 1e3 * s.max_error[1],
              1e3 * s.max_error[2]);
  if (s.colour_by) {
    const FieldLegend& l = *s.colour_by;
    std::printf("  coloured by %s (%s, %s to %s): %llu of %llu points outside the range, %llu without a value (grey)\n",
                l.field.c_str(), FieldScaleName(l.scale), FormatDouble(l.lo).c_str(), FormatDouble(l.hi).c_str(),
                static_cast<unsigned long long>(l.outside), static_cast<unsigned long long>(l.count),
                static_cast<unsigned long long>(l.undefined));
  }
  return kOk;
}

void AddPack(Command& root) {
  PackArgs& a = root.Keep<PackArgs>();
  Command c = root.Add("pack", "Pack point files into a render archive: Morton-ordered chunks, 8 bytes a point, "
                               "memory-mapped by `candi render ARCHIVE`");
  c.Option("inputs", a.inputs, "Point files " CANDI_POINT_FILES_READ).Required();
  c.Option("-o,--output", a.output, "Archive directory (replaced if it is an archive)").Required();
  c.Option("--chunk-points", a.options.chunk_points, "Points per chunk at most").Range(64, 1 << 24);
  c.Option("--memory", a.memory_mb, "MB for sorting (larger inputs are bucketed on disk)");
  c.Option("--columns", a.columns, "XYZ/PTS column spec");
  c.Option("--threads", a.options.threads, "Threads (0: all)").Range(0, 256);
  AddFieldColouring(c, a.field);
  c.Run([&a] { return RunPack(a); });
  c.Footer("Example: candi pack site.las photos.ply -o site.archive && candi render site.archive -o site.png   "
           "(candi pack deviations.ply --colour-by distance -o dev.archive: render, view and publish show its "
           "legend)");
}

struct ExportCopcArgs {
  pipeline::CopcExportOptions options;
  double copc_memory_mb = 0;
};

int RunExportCopc(const ExportCopcArgs& a) {
  pipeline::CopcExportOptions o = a.options;
  o.copc.memory_bytes = CopcMemoryBytes(a.copc_memory_mb);
  std::optional<ConsoleProgress> progress;  // from the first point: no bar before an error
  StagedProgress closing("copc");            // each file's octree and chunks, once all is read
  const std::vector<pipeline::CopcFile> files = pipeline::ExportCopc(
      o,
      [&](uint64_t done, uint64_t total) {
        if (!progress) progress.emplace("copc");
        progress->Update(done, total);
        if (total > 0 && done >= total) progress->Finish();  // all read: the files close next
      },
      closing.Callback());
  closing.Finish();
  if (progress) progress->Finish();
  for (const pipeline::CopcFile& f : files) {
    std::printf("%s: %llu points (%s), %llu bytes\n", f.path.c_str(), static_cast<unsigned long long>(f.points),
                f.layer.empty() ? "every layer, point source ID = layer index" : ("layer " + f.layer).c_str(),
                static_cast<unsigned long long>(f.bytes));
  }
  return kOk;
}

void AddExport(Command& root) {
  Command e = root.Add("export", "Write a finished build's layers in another format, without rebuilding");
  e.RequireSubcommand();
  ExportCopcArgs& a = root.Keep<ExportCopcArgs>();
  pipeline::CopcExportOptions& o = a.options;
  Command c = e.Add("copc", "COPC (cloud-optimized LAZ) of a finished build, for Potree, QGIS and CloudCompare: "
                            "every layer in one file, the layer as point source ID, and with --layers each layer "
                            "beside its PLY (what a scene's \"copc\" makes candi build write)");
  c.Option("build", o.build, "A finished build's folder (archive.json, layers/)").Required();
  c.Option("-o,--out", o.out, "The whole scene's file (default: BUILD/copc/<scene>.copc.laz)");
  c.Flag("--layers", o.copc.layers, "Also each layer as BUILD/layers/<name>.copc.laz");
  AddCopcMemory(c, a.copc_memory_mb);
  c.Run([&a] { return RunExportCopc(a); });
  c.Footer("Example: candi export copc borobudur_archive --layers   (then open "
           "borobudur_archive/copc/borobudur.copc.laz in QGIS, or with Potree)");
}

}  // namespace

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

void AddAssembleCommands(Command& root) {
  AddBuild(root);
  AddPack(root);
  AddExport(root);
}

}  // namespace candi::apps

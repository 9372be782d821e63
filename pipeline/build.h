// The integrated archive of a scene (pipeline/scene.h): every layer digitized by its own path,
// moved into the scene's one frame, written, packed and rendered, with its provenance. What
// `candi build` and `candi demo` run.
//
// Each layer is digitized by its path (a point file read; a foundation from its DXF; relief
// panels from photos through the depth network, placed by Ceres; photogrammetry from photos or a
// dense workspace, georeferenced), transformed into the scene's CRS with PROJ, then by
// world_from_layer into the scene's one LocalFrame, and written as:
//   layers/<name>.ply      double world coordinates (no shift, so every tool reads them as they are),
//                          colours, scalar_scene_layer (the layer index; CloudCompare keeps it) and a
//                          quality copy (MeshLab keeps that one)
//   archive/               the render archive of every layer (render/archive_pack.h)
//   renders/<view>.png     one SPBR render per view, and its .view.json (repeatable)
//   meshlab/               float local-coordinate PLYs, scene.mlp and shift.txt
//   archive.json           the build's record (render/build_record.h): provenance (sources and hashes,
//                          method, parameters, seed, version, counts, what makes the build
//                          reproducible) and the render settings it resolved; no run times, so that
//                          two builds of the same input give the same bytes
//   compare/<name>.ply     each of the scene's comparisons (scene.h, "comparisons"; pipeline/compare.h):
//                          the compared layer's points (world) with their distances, and beside it
//                          .compare.json, .histogram.svg and .report.md; archive.json lists each
//                          with its headline figures
//   layers/<name>.copc.laz, copc/<scene>.copc.laz
//                          COPC for Potree, QGIS and CloudCompare, when the scene's "copc" asks
//                          (pipeline/copc_export.h: the layer as point source ID, the scene's CRS
//                          as WKT); archive.json's "copc" lists each with its points and bytes
//   timings.json           seconds per layer, the pack, each view, each comparison, the COPC files
//                          and in all
// Intermediate files go to work/ (the stages' own outputs: the foundation's and the dense cloud's
// points, relief depth maps and panel points, COLMAP's workspace). The layers are digitized, placed
// and rendered in memory; relief panels pass through their files (they may come from child
// processes), and the comparisons, the render archive and the COPC files are made from the layer
// files (layers/<name>.ply).
// Every file is written atomically.
//
// Resuming (options.resume): every finished stage that is worth keeping (a digitized foundation,
// relief or photogrammetry layer; the render archive; each render; each comparison; the COPC
// files, redone when one is missing) leaves a
// checkpoint in work/checkpoints/<stage>.json holding a key: the SHA-256 of what the stage depends
// on (candi's version, the scene's JSON for it, the seed, the bytes of every input file (a dense
// workspace: its files' names, sizes and times; a comparison: the layer files it reads), the keys
// of the stages it uses). A resumed build redoes
// only stages whose key differs or whose outputs are missing; archive.json marks what was reused
// ("resumed": true). An interrupted build (SIGINT, core/interrupt.h) leaves finished stages
// complete and nothing half-written.
// Failures: std::invalid_argument for invalid options, InputError naming the file and the failing
// stage otherwise. Not thread-safe (one build per process).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/local_frame.h"
#include "pipeline/scene.h"
#include "reconstruction/relief/panel_size.h"

namespace candi::pipeline {

// One relief panel through the depth network: photo -> depth map -> metric points in the panel
// frame (x along the wall, y up, z out; reconstruction/relief/relief_points.h).
struct ReliefPanelJob {
  std::string photo, model;
  double predict_width_m = 0;  // the panel's width in the photo for the network (0: the photo's own resolution)
  double width_m = relief::kPanelWidthM;  // the panel's width for its points, m
  std::string depth;           // the depth map to write (8-bit PNG levels)
  std::string points;          // the panel's points to write (PLY)
  std::string log_base;        // <work>/<layer>_<panel>: child processes' logs
};
// Runs a panel's job, writing job.depth and job.points; throws InputError on failure.
using ReliefPanelRunner = std::function<void(const ReliefPanelJob& job)>;
// Runs each job as `candi-relief relief predict` and `relief points` child processes beside this
// executable, so that an executable without the relief path never loads libtorch.
ReliefPanelRunner ReliefInChildProcesses();

struct BuildOptions {
  std::string output;          // the build folder (created; its parent must exist)
  int threads = 0;             // renders, packing, sampling: [0, 256], 0 = all
  bool resume = false;         // reuse the stages an earlier (interrupted) build finished
  uint64_t copc_memory_bytes = 0;  // the scene's COPC files: CopcOptions::memory_bytes
  ReliefPanelRunner relief;    // empty: ReliefInChildProcesses()
  void Check() const;
};

struct BuildLayerSummary {
  std::string name;
  LayerKind kind = LayerKind::kPoints;
  uint64_t points = 0;
  double opacity = 1;
  bool scanned = false;        // measured data (points, photogrammetry), not reconstructed
  double seconds = 0;          // digitizing it (0 when resumed)
};

// A comparison of the scene (scene.h, "comparisons"), as archive.json lists it.
struct BuildComparisonSummary {
  std::string name, method;
  uint64_t count = 0;               // compared points
  double mean = 0, rms = 0;         // m; NaN when no distance is defined
  double tolerance = 0;             // m
  double within_tolerance = 0;      // share of the defined distances, [0, 1]; NaN when none
  bool resumed = false;
};

struct BuildSummary {
  std::vector<BuildLayerSummary> layers;
  std::vector<BuildComparisonSummary> comparisons;
  uint64_t points = 0;
  LocalFrame frame;            // the scene's frame
  size_t views = 0;            // renders
  double seconds = 0;
};

BuildSummary Build(const BuildOptions& options, const Scene& scene);

}  // namespace candi::pipeline

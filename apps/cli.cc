// The `candi` command line: every subcommand's options, in one translation unit (CLI11 is heavy).
#include <CLI/CLI.hpp>

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "apps/commands.h"
#include "apps/logging.h"
#include "core/progress.h"
#include "core/version.h"

namespace candi::app {

namespace {

void AddInfo(CLI::App& app, InfoArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("info", "Print a point file's count, bounds (world), fields, format (LAZ: its compressor), shift and CRS");
  c->add_option("file", a.input, "Point file (.ply .las .laz .e57 .xyz .txt .pts)")->required();
  c->add_option("--columns", a.columns, "XYZ/PTS column spec, e.g. x,y,z,r,g,b");
  c->add_flag("--json", a.json, "Print JSON instead of text");
  c->add_flag("--no-scan", a.no_scan, "Header only: do not read the points (bounds from the header)");
  c->callback([run, &a] { *run = [&a] { return RunInfo(a); }; });
  c->footer("Example: candi info site.las");
}

void AddConvert(CLI::App& app, ConvertArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("convert", "Convert between PLY, LAS, E57, XYZ and PTS (and read LAZ), streaming; reproject with PROJ");
  c->add_option("input", a.input, "Input point file")->required();
  c->add_option("output", a.output, "Output point file; format from its extension")->required();
  c->add_option("--shift", a.shift,
                "Output origin shift: auto (rounded centre when coordinates exceed 1e4 m), none, "
                "or x,y,z; default: keep the input's");
  c->add_option("--columns", a.columns, "Input XYZ/PTS column spec, e.g. x,y,z,r,g,b");
  c->add_option("--out-columns", a.out_columns, "Output XYZ/PTS column spec");
  c->add_option("--ply-encoding", a.ply_encoding, "PLY output: binary, binary_be or ascii")
      ->check(CLI::IsMember({"binary", "binary_be", "ascii"}));
  c->add_option("--precision", a.precision, "PLY/XYZ positions: auto, float or double")
      ->check(CLI::IsMember({"auto", "float", "double"}));
  c->add_option("--las-scale", a.las_scale, "LAS output scale, s or sx,sy,sz (default: keep, else 0.001)");
  c->add_option("--las-format", a.las_format, "LAS output point format: 0-3 or 6-8");
  c->add_option("--las-version", a.las_version, "LAS output minor version: 2, 3 or 4");
  c->add_option("--crs", a.crs, "The input's CRS (e.g. EPSG:4979), for files that state none; "
                "carried into the output");
  c->add_option("--to-crs", a.to_crs, "Reproject into this CRS with PROJ (e.g. EPSG:32749)");
  c->callback([run, &a] { *run = [&a] { return RunConvert(a); }; });
  c->footer("Examples: candi convert scan.las scan.ply --shift auto\n"
            "          candi convert gnss_wgs84.laz site_utm.las --to-crs EPSG:32749");
}

void AddDemo(CLI::App& app, DemoArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("demo", "Build and render the bundled example");
  c->add_option("-o,--output", a.output_dir, "Output folder");
  c->add_option("--width", a.width, "Image width in pixels")->check(CLI::Range(16, 16384));
  c->add_option("--height", a.height, "Image height in pixels")->check(CLI::Range(16, 16384));
  c->add_option("--seed", a.seed, "Random seed");
  auto* quick = c->add_flag("--quick", a.quick, "The reduced scene (fewer points, L = 32), as CI runs it");
  c->add_flag("--full", a.full, "Paper scale: all 160 relief panels through the network at the model's "
              "resolution (default: the 156 hidden ones at their photos' own, 8x fewer tiles)")
      ->excludes(quick);
  c->callback([run, &a] { *run = [&a] { return RunDemo(a); }; });
  c->footer("Example: candi demo -o demo_out");
}

void AddOpacity(CLI::App& app, OpacityArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("opacity", "Set SPBR opacity by point-number adjustment: removes or "
                               "replicates points (field spbr_multiplicity) for a target alpha");
  c->add_option("input", a.input, "Input point file")->required();
  c->add_option("output", a.output, "Output point file; format from its extension")->required();
  c->add_option("--alpha", a.alpha, "Target opacity, 0..1")->required();
  c->add_option("--repeat-level", a.repeat_level, "L, the number of ensembles the renderer averages")
      ->required();
  c->add_option("--image-size", a.image_size, "Pixels across the cloud's largest extent");
  c->add_option("--pixel-size", a.pixel_size, "Or: the pixel footprint's side, metres");
  c->add_option("--seed", a.seed, "Random seed");
  auto* k = c->add_option("--neighbours", a.neighbours, "Neighbours of the median point for the "
                          "automatic density radius (default 32)");
  c->add_option("--radius", a.radius, "Density radius, metres (default: automatic)")->excludes(k);
  c->add_option("--method", a.method, "Density estimate: kdtree or voxel")
      ->check(CLI::IsMember({"kdtree", "voxel"}));
  c->add_option("--threads", a.threads, "Worker threads (0 = all)");
  c->callback([run, &a] { *run = [&a] { return RunOpacity(a); }; });
  c->footer("Example: candi opacity site.ply site_a05.ply --alpha 0.5 --repeat-level 100 "
            "--image-size 1024");
}

void AddClip(CLI::App* c, ClipArgs& clip) {
  c->add_option("--clip-box", clip.box, "Keep only points inside this box, world (survey) coordinates: "
                "xmin,ymin,zmin,xmax,ymax,zmax");
  c->add_option("--clip-plane", clip.planes, "Keep only the side of a plane its normal points into: "
                "px,py,pz,nx,ny,nz (world coordinates; repeat for several)")->expected(1)->take_all();
}

void AddRender(CLI::App& app, RenderArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("render", "Render point files see-through with SPBR (stochastic "
                                         "point-based rendering), merged into one image");
  c->add_option("inputs", a.inputs, "Point files (.ply .las .xyz .pts), or one archive (candi pack); "
                "under mpirun the ranks share the ensembles")->required();
  c->add_option("-o,--output", a.output, "Output PNG (8-bit)")->required();
  c->add_option("--png16", a.output16, "Also write a 16-bit PNG (for analysis)");
  c->add_option("-L,--repeat-level", a.repeat_level, "Ensembles averaged (more: less noise, slower)");
  c->add_option("--seed", a.seed, "Seed of the ensemble assignment");
  c->add_option("--size", a.size, "Image size WxH")->each([&a](const std::string&) { a.size_given = true; });
  c->add_option("--view", a.view, "View JSON (world coordinates) to render from");
  c->add_option("--save-view", a.save_view, "Write the view used as JSON (to repeat the render)");
  c->add_option("--background", a.background, "Background colour r,g,b");
  c->add_option("--brightness", a.brightness, "auto, none, or a gain (transparent images get dark)");
  c->add_option("--alpha", a.alpha, "Target opacity per input (one value for all, or one each)")
      ->delimiter(',');
  c->add_flag("--opaque", a.opaque, "Opaque rendering (L = 1, one point per pixel)");
  c->add_option("--threads", a.threads, "Threads (0: all)")->check(CLI::Range(0, 256));
  c->add_option("--point-size", a.point_size, "Point size in pixels (>= 1; stochastic rounding)");
  c->add_option("--preview", a.preview, "Render only the first k ensembles (progressive preview)");
  c->add_option("--mode", a.mode, "auto, memory (fast, 10 B/point) or stream (bounded memory)");
  c->add_option("--memory-budget", a.memory_mb, "Stream mode and archives: MB of z-buffers resident per pass (12 B per pixel and ensemble)");
  c->add_option("--chunk-budget", a.chunk_budget_mb, "Archive input: MB of chunks mapped at once (8 B a point)");
  c->add_option("--columns", a.columns, "XYZ/PTS column spec");
  c->add_option("--up", a.up, "Without --view: world up, x,y,z (default 0,0,1; COLMAP's frame: 0,-1,0)");
  c->add_option("--from", a.from, "Without --view: the direction the view looks in, x,y,z (default: oblique, from above)");
  c->add_option("--cameras", a.cameras, "Without --view: a COLMAP model (e.g. WORK/sparse/0) whose frame the points "
                "are in: up and the viewing side from its cameras");
  AddClip(c, a.clip);
  c->callback([run, &a] { *run = [&a] { return RunRender(a); }; });
  c->footer("Example: candi render building.ply foundation.ply -o site.png -L 100 --alpha 0.3,0.8");
}

void AddView(CLI::App& app, ViewArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("view", "Open an archive in the browser: orbit it see-through while the server "
                                       "renders (SPBR), the image refining as you watch");
  c->add_option("inputs", a.inputs, "A build directory (candi build), a render archive (candi pack), or "
                "point files (packed on the fly into a temporary archive)")->required();
  c->add_option("--host", a.host, "Address to serve on (default 127.0.0.1; 0.0.0.0 serves your network: "
                "anyone with the printed address and token sees the data)");
  c->add_option("--port", a.port, "Port (0: any free one)")->check(CLI::Range(0, 65535));
  c->add_option("--up", a.up, "World up for the first view, x,y,z (default 0,0,1; COLMAP's frame: 0,-1,0)");
  c->add_option("--from", a.from, "Direction the first view looks in, x,y,z (default: oblique, from above)");
  c->add_option("--cameras", a.cameras, "A COLMAP model (e.g. WORK/sparse/0) whose frame the points are in: the "
                "first view's up and side from its cameras");
  c->add_option("--columns", a.columns, "XYZ/PTS column spec");
  c->add_option("--threads", a.threads, "Render threads (0: all)")->check(CLI::Range(0, 256));
  AddClip(c, a.clip);
  c->callback([run, &a] { *run = [&a] { return RunView(a); }; });
  c->footer("Example: candi view borobudur_out/   (then open the printed http://127.0.0.1:8765/?token=... address)");
}

void AddSection(CLI::App& app, SectionArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("section", "Cut a slab out of an archive or point files: a see-through image of "
                                          "it and its section lines per layer (DXF, CSV, SVG), in survey coordinates");
  c->add_option("inputs", a.inputs, "An archive (candi pack), a build directory (candi build), or point files "
                "(a file's layer field names its layers)")->required();
  c->add_option("-o,--output", a.output, "Output directory: section.png, .dxf, .csv, .svg and .json")->required();
  c->add_option("--plane", a.plane, "A plane through a point with a normal: px,py,pz,nx,ny,nz (world coordinates)");
  c->add_option("--through", a.through, "The vertical plane through two survey points, chainage from the first: "
                "x1,y1,x2,y2 (or with z)");
  c->add_option("--path", a.path, "A plan polyline x1,y1,x2,y2,...: its vertical faces unrolled into one section");
  c->add_option("--thickness", a.thickness, "Slab thickness in metres (> 0)")->required();
  c->add_option("--spacing", a.spacing, "Section lines: vertex spacing in metres (0: from the points' density)");
  c->add_option("--max-gap", a.max_gap, "Section lines: a gap in the data longer than this breaks a line (0: automatic)");
  c->add_option("--width", a.width, "Image width in pixels");
  c->add_option("--pixel", a.pixel, "Image: metres per pixel (overrides --width)");
  c->add_option("-L,--repeat-level", a.repeat_level, "Image: SPBR ensembles");
  c->add_option("--seed", a.seed, "Image: seed of the ensembles");
  c->add_option("--point-size", a.point_size, "Image: point size in pixels");
  c->add_option("--opacity", a.opacity, "Image: opacity of a pixel one point covers, (0, 1]; overlapping layers "
                "blend as SPBR blends");
  c->add_option("--colours", a.colours, "Image colours: layer (one per layer) or data (the points' own)");
  c->add_option("--background", a.background, "Image background r,g,b");
  c->add_option("--layers", a.layers, "Only these layers (names)")->delimiter(',');
  c->add_option("--columns", a.columns, "XYZ/PTS column spec");
  c->add_option("--threads", a.threads, "Threads (0: all)")->check(CLI::Range(0, 256));
  AddClip(c, a.clip);
  c->callback([run, &a] { *run = [&a] { return RunSection(a); }; });
  c->footer("Example: candi section borobudur_out/ --through 0,-60,0,60 --thickness 0.2 -o section_ns/");
}

void AddBench(CLI::App& app, BenchArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("bench", "Benchmarks: `candi bench render` prints SPBR accuracy vs "
                                        "time for L = 1 ... 1024");
  c->add_option("what", a.what, "What to measure: render (SPBR), foundation (sections to points), "
                 "dense (PatchMatch on the synthetic scene)")
      ->check(CLI::IsMember({"render", "foundation", "dense"}));
  c->add_option("--points", a.points, "Points in the generated scene");
  c->add_option("--width", a.width, "Image width")->check(CLI::Range(16, 8192));
  c->add_option("--height", a.height, "Image height")->check(CLI::Range(16, 8192));
  c->add_option("--threads", a.threads, "Threads (0: all)")->check(CLI::Range(0, 256));
  c->add_option("--data", a.data, "dense: the shared data folder; runs candi dense on its Sceaux photos "
                "against its OpenMVS cloud instead of the synthetic table");
  c->add_option("--scale", a.scale, "dense --data: resolution scale")->check(CLI::Range(0.05, 1.0));
  c->add_option("--iterations", a.iterations, "dense --data: PatchMatch rounds")->check(CLI::Range(1, 50));
  c->callback([run, &a, c] {
    if (!c->get_subcommands().empty()) return;  // `bench relief`, `bench scale` (got_subcommand throws for absent ones)
    *run = [&a] { return RunBench(a); };
  });
  c->footer("Example: candi bench render --points 1000000; candi bench dense --data ../shared/data --threads 2");
}


void AddPack(CLI::App& app, PackArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("pack", "Pack point files into a render archive: Morton-ordered chunks, "
                               "8 bytes a point, memory-mapped by `candi render ARCHIVE`");
  c->add_option("inputs", a.inputs, "Point files (.ply .las .xyz .pts)")->required();
  c->add_option("-o,--output", a.output, "Archive directory (replaced if it is an archive)")->required();
  c->add_option("--chunk-points", a.chunk_points, "Points per chunk at most")->check(CLI::Range(64, 1 << 24));
  c->add_option("--memory", a.memory_mb, "MB for sorting (larger inputs are bucketed on disk)");
  c->add_option("--columns", a.columns, "XYZ/PTS column spec");
  c->add_option("--threads", a.threads, "Threads (0: all)")->check(CLI::Range(0, 256));
  c->callback([run, &a] { *run = [&a] { return RunPack(a); }; });
  c->footer("Example: candi pack site.las photos.ply -o site.archive && candi render site.archive -o site.png");
}

void AddBenchScale(CLI::App& app, BenchScaleArgs& a, std::function<int()>* run) {
  auto* c = app.get_subcommand("bench")->add_subcommand(
      "scale", "Pack and render generated scenes of 1e7, 1e8 (1e9) points: points/s, s/frame, peak RSS");
  c->add_option("--sizes", a.sizes, "Point counts, comma separated");
  c->add_flag("--billion", a.billion, "Also 1e9 points (~8 GB archive, ~28 GB temporary disk, minutes)");
  c->add_option("--work-dir", a.work_dir, "Folder for the generated data (deleted afterwards)");
  c->add_option("--size", a.size, "Image size WxH");
  c->add_option("-L,--repeat-level", a.repeat_level, "Ensembles");
  c->add_option("--ranks", a.ranks, "mpirun -np for the MPI runs (0: none)")->check(CLI::Range(0, 64));
  c->add_flag("--keep", a.keep, "Keep the generated data");
  c->callback([run, &a] { *run = [&a] { return RunBenchScale(a); }; });
  c->footer("Example: candi bench scale --sizes 1e7");
}

void AddBenchView(CLI::App& app, BenchViewArgs& a, std::function<int()>* run) {
  auto* c = app.get_subcommand("bench")->add_subcommand(
      "view", "The viewer's renderer on generated archives: first-frame latency (p50/p95) and frames/s during "
              "an orbit, seconds to the converged image, peak memory");
  c->add_option("--sizes", a.sizes, "Point counts, comma separated (e.g. 1e7,1e8)");
  c->add_flag("--billion", a.billion, "Also 1e9 points (~8 GB archive on disk)");
  c->add_option("--work-dir", a.work_dir, "Folder for the generated archive (deleted afterwards)");
  c->add_option("--size", a.size, "Image size WxH");
  c->add_option("-L,--repeat-level", a.repeat_level, "Ensembles of the converged image");
  c->add_option("--threads", a.threads, "Render threads (0: all)")->check(CLI::Range(0, 256));
  c->add_option("--orbit-frames", a.orbit_frames, "Camera changes in the orbit");
  c->add_option("--runs", a.runs, "Convergence runs (the median is printed)")->check(CLI::Range(1, 100));
  c->add_flag("--keep", a.keep, "Keep the generated archives, and reuse those an earlier --keep run kept");
  c->callback([run, &a] { *run = [&a] { return RunBenchView(a); }; });
  c->footer("Example: candi bench view --sizes 1e7,1e8 --threads 2");
}

void AddBenchSection(CLI::App& app, BenchSectionArgs& a, std::function<int()>* run) {
  auto* c = app.get_subcommand("bench")->add_subcommand(
      "section", "Sections: accuracy vs slab thickness on the bundled foundation, and seconds and chunks read "
                 "on generated archives");
  c->add_option("--sizes", a.sizes, "Point counts, comma separated (e.g. 1e7,1e8)");
  c->add_flag("--billion", a.billion, "Also 1e9 points (~8 GB archive on disk)");
  c->add_option("--work-dir", a.work_dir, "Folder for the generated data (shared with bench view)");
  c->add_option("--drawing", a.drawing, "The drawing of the accuracy table (\"\" skips it)");
  c->add_option("--thickness", a.thickness, "Slab thickness of the scale table, m");
  c->add_option("--threads", a.threads, "Threads (0: all)")->check(CLI::Range(0, 256));
  c->add_flag("--keep", a.keep, "Keep the generated archives, and reuse those an earlier --keep run kept");
  c->callback([run, &a] { *run = [&a] { return RunBenchSection(a); }; });
  c->footer("Example: candi bench section --sizes 1e7,1e8 --keep");
}

// `candi relief ...`: the buried-relief path (ALGORITHMS.md section 3).
struct ReliefArgs {
  ReliefSynthArgs synth;
  ReliefDatasetArgs dataset;
  ReliefTrainArgs train;
  ReliefPredictArgs predict;
  ReliefPointsArgs points;
  ReliefEvalArgs eval;
  BenchReliefArgs bench;
  ReliefPlaceArgs place;
};

void AddReliefSynth(CLI::App& relief, ReliefSynthArgs& a, std::function<int()>* run) {
  auto* c = relief.add_subcommand("synth", "Procedural relief panels as old photos with exact depth "
                                           "(NNN_photo.png 8-bit grey, NNN_depth.png 16-bit levels)");
  c->add_option("-o,--output", a.output_dir, "Output folder")->required();
  c->add_option("--count", a.count, "Panels")->check(CLI::Range(1, 100000));
  c->add_option("--width", a.width, "Pixels along the panel")->check(CLI::Range(32, 16384));
  c->add_option("--seed", a.seed, "Random seed of the series");
  c->add_option("--width-m", a.width_m, "Panel width, m");
  c->add_option("--height-m", a.height_m, "Panel height, m");
  c->add_option("--depth-m", a.depth_m, "Relief depth (front plane), m");
  c->add_flag("--no-shadows", a.no_shadows, "No cast shadows");
  c->add_flag("--no-stains", a.no_stains, "Uniform stone albedo");
  c->add_flag("--no-blur", a.no_blur, "No lens blur");
  c->add_flag("--no-grain", a.no_grain, "No film grain");
  c->add_flag("--no-tone", a.no_tone, "No tone curve");
  c->add_flag("--no-fading", a.no_fading, "No fading or vignetting");
  c->callback([run, &a] { *run = [&a] { return RunReliefSynth(a); }; });
  c->footer("Example: candi relief synth -o panels --count 16 --seed 1");
}

void AddReliefDataset(CLI::App& relief, ReliefDatasetArgs& a, std::function<int()>* run) {
  auto* c = relief.add_subcommand("dataset", "Training pairs from scans of visible panels (or from "
                                             "synthetic panels): orthographic render, patches");
  c->add_option("inputs", a.inputs, "Scans (.ply .las .xyz .pts), panel photos (*_photo.png) or "
                                    "folders of them")->required();
  c->add_option("-o,--output", a.output_dir, "Output folder (train/, val/, dataset.txt)")->required();
  c->add_option("--pixels-per-m", a.pixels_per_m, "Render resolution, pixels per metre");
  c->add_option("--patch", a.patch, "Patch side, pixels (multiple of 32)");
  c->add_option("--stride", a.stride, "Step between patches, pixels");
  c->add_option("--val-fraction", a.val_fraction, "Inputs held out for validation")->check(CLI::Range(0.0, 0.9));
  c->add_option("--frame", a.frame, "Scans: panel plane by PCA (auto) or the cloud's x-y (panel)")
      ->check(CLI::IsMember({"auto", "panel"}));
  c->add_option("--depth-m", a.depth_m, "Front plane above the wall, m");
  c->add_option("--panel-width-m", a.panel_width_m, "Width of photo inputs without recorded resolution, m");
  c->add_flag("--no-relight", a.no_relight, "Scans: use the scan's grey, not a raking-light photo");
  c->add_option("--seed", a.seed, "Random seed (simulated photos)");
  auto* colmap = c->add_option("--colmap", a.colmap, "Real photos: a COLMAP sparse model; the inputs are "
                               "dense clouds in its frame (views/, holdout/: whole pairs with masks)");
  auto* images = c->add_option("--images", a.images, "Real photos: the folder of the model's photos");
  colmap->needs(images);
  images->needs(colmap);
  c->add_option("--holdout", a.holdout, "Real photos: images kept out of training (names or stems, "
                "comma-separated)")->delimiter(',');
  c->add_option("--max-side", a.max_side, "Real photos: longer side of a pair, pixels")
      ->check(CLI::Range(32, 16384));
  c->callback([run, &a] { *run = [&a] { return RunReliefDataset(a); }; });
  c->footer("Examples: candi relief dataset scan.ply panels/ -o data --patch 128\n"
            "          candi relief dataset dense.ply --colmap sparse/ --images photos/ --holdout "
            "100_7105.JPG -o pairs --max-side 512");
}

void AddReliefTrain(CLI::App& relief, ReliefTrainArgs& a, std::function<int()>* run) {
  auto* c = relief.add_subcommand("train", "Train the BTS-style depth network (libtorch, CPU)");
  c->add_option("--data", a.data_dir, "Folder from `candi relief dataset`")->required();
  c->add_option("-o,--out", a.output, "Model file to write")->required();
  c->add_option("--epochs", a.epochs, "Epochs")->check(CLI::Range(1, 100000));
  c->add_option("--batch", a.batch, "Batch size")->check(CLI::Range(1, 4096));
  c->add_option("--growth", a.growth, "DenseNet growth rate")->check(CLI::Range(2, 64));
  c->add_option("--blocks", a.blocks, "Dense layers in the 4 blocks, e.g. 4,6,8,6");
  c->add_option("--width", a.decoder_width, "Decoder width (BTS num_features; multiple of 16)");
  c->add_option("--lr", a.learning_rate, "Start learning rate");
  c->add_option("--end-lr", a.end_learning_rate, "End learning rate (polynomial decay, power 0.9)");
  c->add_option("--max-seconds", a.max_seconds, "Stop after this many seconds (0: no limit)");
  c->add_option("--checkpoint", a.checkpoint, "Checkpoint file (default: <out>.ckpt)");
  c->add_flag("--resume", a.resume, "Continue from the checkpoint");
  auto* finetune = c->add_option("--finetune", a.finetune, "Start from this model's weights with a fresh "
                                 "optimiser (e.g. the shipped model on pairs of real photos)");
  for (const char* net : {"--growth", "--blocks", "--width"}) finetune->excludes(c->get_option(net));
  c->add_option("--edge-loss", a.edge_weight, "Weight of the edge term (log-depth differences 1, 2, 4 "
                "pixels apart; 0: off)")->check(CLI::Range(0.0, 1000.0));
  c->add_option("--seed", a.seed, "Random seed (weights, order, augmentation)");
  c->add_option("--threads", a.threads, "libtorch threads")->check(CLI::Range(1, 256));
  c->callback([run, &a] { *run = [&a] { return RunReliefTrain(a); }; });
  c->footer("Examples: candi relief train --data data --out model.pt --epochs 20\n"
            "          candi relief train --data pairs --finetune examples/relief/relief_model.pt "
            "--out tuned.pt --lr 3e-4 --epochs 4");
}

void AddReliefPredict(CLI::App& relief, ReliefPredictArgs& a, std::function<int()>* run) {
  auto* c = relief.add_subcommand("predict", "Depth of a photo of any size (overlapping tiles, "
                                             "blended without seams)");
  c->add_option("photo", a.photo, "Photo (PNG, 8/16-bit, grey or colour)")->required();
  c->add_option("--model", a.model, "Model file")->required();
  c->add_option("-o,--output", a.output, "Depth PNG (8-bit levels, 0 = front plane, 255 = wall)")->required();
  c->add_option("--png16", a.output16, "Also write 16-bit depth (levels x 256)");
  c->add_option("--width-m", a.width_m, "The panel's width in the photo, m (0: photo is at the "
                                        "model's resolution)");
  c->add_option("--tile", a.tile, "Tile side, pixels (multiple of 32)");
  c->add_option("--overlap", a.overlap, "Tile overlap, pixels");
  c->add_option("--threads", a.threads, "libtorch threads")->check(CLI::Range(1, 256));
  c->callback([run, &a] { *run = [&a] { return RunReliefPredict(a); }; });
  c->footer("Example: candi relief predict photo.png --model model.pt -o depth.png");
}

void AddReliefPoints(CLI::App& relief, ReliefPointsArgs& a, std::function<int()>* run) {
  auto* c = relief.add_subcommand("points", "Metric points of a panel from its photo and depth map "
                                            "(panel frame: x along the wall, y up, z out)");
  c->add_option("photo", a.photo, "Photo (grey becomes the colour)")->required();
  c->add_option("depth", a.depth, "Depth PNG (levels)")->required();
  c->add_option("-o,--output", a.output, "Point file (.ply .las .xyz .pts)")->required();
  c->add_option("--width-m", a.width_m, "Panel width, m");
  c->add_option("--height-m", a.height_m, "Panel height, m");
  c->add_option("--depth-m", a.depth_m, "Relief depth: level 0 is this far out of the wall, m");
  c->callback([run, &a] { *run = [&a] { return RunReliefPoints(a); }; });
  c->footer("Example: candi relief points photo.png depth.png -o panel.ply --width-m 2.7 "
            "--height-m 0.92 --depth-m 0.15");
}

void AddReliefEval(CLI::App& relief, ReliefEvalArgs& a, std::function<int()>* run) {
  auto* c = relief.add_subcommand("eval", "The paper's Table 2 metrics: model, intensity-as-depth, "
                                          "linear SFS and the paper's BTS");
  c->add_option("--model", a.models, "Model file, repeatable (without it: the baselines only)");
  c->add_option("--panels", a.panels, "Held-out synthetic panels")->check(CLI::Range(1, 10000));
  c->add_option("--width", a.width, "Their width, pixels")->check(CLI::Range(32, 16384));
  c->add_option("--seed", a.seed, "Their seed (keep it apart from the training seeds)");
  c->add_option("--photo", a.photo, "Or: one photo ...");
  c->add_option("--depth", a.depth, "... and its ground-truth depth PNG");
  c->add_option("--pairs", a.pairs, "Or: a folder of <name>_photo.png + _depth.png [+ _mask.png] pairs "
                "(real photos: `relief dataset --colmap`), scored as they are (no resampling)");
  c->add_option("--level-per-pixel", a.level_per_pixel, "Normals: one depth level in pixel widths "
                "(default: depth_m/255 over the panel's metres per pixel; 1 for --pairs)");
  c->add_option("--normal-step", a.normal_step, "Normals: differences over this many pixels each side "
                "(default 1; 4 for --pairs, whose depth is noisy at one pixel)")->check(CLI::Range(1, 16));
  c->add_option("--edge-jump", a.edge_jump, "Edges: a depth step of more than this many levels")
      ->check(CLI::Range(0.001, 255.0));
  c->add_option("--edge-tolerance", a.edge_tolerance, "Edges: match within this many pixels")
      ->check(CLI::Range(0, 16));
  c->add_option("--light-azimuth", a.light_azimuth, "SFS light azimuth, degrees (default: from the photo)");
  c->add_option("--light-elevation", a.light_elevation, "SFS light elevation, degrees");
  c->add_option("--width-m", a.width_m, "Panel width in --photo, m");
  c->add_option("--tile", a.tile, "Tile side, pixels");
  c->add_option("--overlap", a.overlap, "Tile overlap, pixels");
  c->add_option("--threads", a.threads, "libtorch threads")->check(CLI::Range(1, 256));
  c->callback([run, &a] { *run = [&a] { return RunReliefEval(a); }; });
  c->footer("Examples: candi relief eval --model examples/relief/relief_model.pt --panels 4\n"
            "          candi relief eval --pairs pairs/holdout --model examples/relief/relief_model.pt "
            "--model tuned.pt");
}

void AddBenchRelief(CLI::App& app, BenchReliefArgs& a, std::function<int()>* run) {
  auto* c = app.get_subcommand("bench")->add_subcommand(
      "relief", "Relief depth: network width x training time -> accuracy, training and "
                "prediction seconds, 3200x1024 photo -> points");
  c->add_option("--widths", a.widths, "Decoder widths to train, e.g. 32,64,128");
  c->add_option("--seconds", a.seconds, "Training budget per width, s");
  c->add_option("--train-panels", a.train_panels, "Synthetic training panels")->check(CLI::Range(1, 10000));
  c->add_option("--eval-panels", a.eval_panels, "Held-out panels")->check(CLI::Range(1, 10000));
  c->add_option("--seed", a.seed, "Seed of the training series");
  c->add_option("--threads", a.threads, "libtorch threads")->check(CLI::Range(1, 256));
  c->add_option("--pairs", a.pairs, "Real photos instead: a `relief dataset --colmap` folder; the model "
                "is fine-tuned on train/ for each budget and scored on holdout/");
  c->add_option("--model", a.model, "Real photos: the model to fine-tune");
  c->add_option("--finetune-seconds", a.finetune_seconds, "Real photos: fine-tuning budgets, s");
  c->add_option("--edge-loss", a.edge_weight, "Weight of the edge term in the edge-guided "
                "rows (0: plain rows only)")->check(CLI::Range(0.0, 1000.0));
  c->add_option("--lr", a.learning_rate, "Real photos: fine-tuning learning rate");
  c->callback([run, &a] { *run = [&a] { return RunBenchRelief(a); }; });
  c->footer("Examples: candi bench relief --widths 32,64 --seconds 60\n"
            "          candi bench relief --pairs pairs --model examples/relief/relief_model.pt "
            "--finetune-seconds 60,240");
}

void AddReliefPlace(CLI::App& relief, ReliefPlaceArgs& a, std::function<int()>* run) {
  auto* c = relief.add_subcommand("place", "Each panel's world_from_panel by a robust rigid or Sim3 "
                                  "fit (Ceres) of its corners / edge points to documented wall "
                                  "positions; residuals per panel, misfits warned");
  c->add_option("correspondences", a.correspondences, "CSV: panel,point,x,y,z,E,N,H[,accuracy]")
      ->required();
  c->add_option("-o,--output", a.output, "Placements JSON (world_from_panel, residuals)")->required();
  c->add_option("--panels", a.panels, "The panels' point files, named <panel>.ply, or folders of them");
  c->add_option("--points-out", a.points_out, "Folder for the panels in world coordinates (double, "
                "shifted; with --panels)");
  c->add_flag("--sim3", a.sim3, "Estimate the scale too (default: rigid, the points are metric)");
  c->add_option("--loss", a.loss, "Robust loss: huber, cauchy or none")
      ->check(CLI::IsMember({"none", "huber", "cauchy"}));
  c->add_option("--loss-scale", a.loss_scale, "Robust loss scale, m")->check(CLI::PositiveNumber);
  c->add_option("--accuracy", a.accuracy, "Accuracy of positions without one in the CSV, m")
      ->check(CLI::PositiveNumber);
  c->add_option("--tolerance-mm", a.tolerance_mm, "A panel whose RMS residual exceeds this does "
                "not fit (a warning)")->check(CLI::PositiveNumber);
  c->callback([run, &a] { *run = [&a] { return RunReliefPlace(a); }; });
  c->footer(
      "CSV: one row per point of a panel: panel id, point name (unique per panel), x,y,z in the\n"
      "panel frame of `relief points` (m: x along the wall from the left edge, y up from the bottom\n"
      "edge, z out of the wall; the corners of a W x H panel are (0,0,0), (W,0,0), (W,H,0), (0,H,0)),\n"
      "E,N,H its documented position on the wall (m), optional accuracy (m). >= 3 points per panel.\n"
      "Exit 0 also when panels do not fit (status 'misfit' or 'collinear' in the table and JSON,\n"
      "a warning each); exit 2 for bad input (file, line and field named), nothing written.\n"
      "Example: candi relief place walls.csv -o placements.json --panels panels/ --points-out world/");
}

void AddRelief(CLI::App& app, ReliefArgs& a, std::function<int()>* run) {
  auto* relief = app.add_subcommand("relief", "Buried reliefs from one old photo: synth, dataset, "
                                              "train, predict, points, eval, place");
  relief->require_subcommand(1);
  AddReliefSynth(*relief, a.synth, run);
  AddReliefDataset(*relief, a.dataset, run);
  AddReliefTrain(*relief, a.train, run);
  AddReliefPredict(*relief, a.predict, run);
  AddReliefPoints(*relief, a.points, run);
  AddReliefEval(*relief, a.eval, run);
  AddReliefPlace(*relief, a.place, run);
}


void AddBuild(CLI::App& app, BuildArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("build", "Build the integrated archive of a scene file: every layer "
                               "digitized, placed in one frame, written per layer, packed, rendered, "
                               "with provenance (archive.json) and a MeshLab project");
  c->add_option("scene", a.scene, "Scene JSON (format: apps/scene.h, README)")->required();
  c->add_option("-o,--output", a.output, "Archive folder")->required();
  c->add_option("--threads", a.threads, "Threads (0: all)")->check(CLI::Range(0, 256));
  c->add_flag("--resume", a.resume, "Reuse what an earlier build into the same folder finished (its "
              "digitized layers, archive and renders) where their inputs are unchanged");
  c->callback([run, &a] { *run = [&a] { return RunBuild(a); }; });
  c->footer("Example: candi build examples/borobudur/scene.json -o borobudur_archive");
}

void AddFoundation(CLI::App& app, FoundationArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("foundation", "Foundation layers from a CAD section drawing (DXF): "
                               "profiles, Hermite resampling, rotational blending or sweep, mesh, "
                               "uniform points");
  c->add_option("drawing", a.input, "Section drawing (ASCII DXF)")->required();
  c->add_option("-o,--output", a.output, "Point file (.ply .las .xyz .pts): merged with a layer "
                "field, or one per layer with --split")->required();
  c->add_option("--layers", a.layers, "Layers to build, e.g. A,B,C,D (default: all with a "
                "section)")->delimiter(',');
  c->add_option("--samples-per-side", a.samples_per_side, "N: Hermite samples per side (>= 2)");
  c->add_option("--angular-steps", a.angular_steps, "M: steps per half-turn (>= 2)");
  auto* count = c->add_option("--count", a.count, "Total points, split over the layers by area");
  auto* density = c->add_option("--density", a.density, "Points per m^2 (default 50)");
  auto* per = c->add_option("--per-triangle", a.per_triangle, "The paper's mode: this many points "
                            "in every triangle (not uniform; for comparison)");
  count->excludes(density);
  per->excludes(count)->excludes(density);
  c->add_option("--mode", a.mode, "auto (sweep symmetric layers, blend the others), blend or "
                "sweep")->check(CLI::IsMember({"auto", "blend", "sweep"}));
  c->add_option("--mesh", a.mesh, "Also write the mesh (.obj .off .ply); <stem>_<layer><ext> "
                "when several layers");
  c->add_flag("--split", a.split, "One point file per layer: <stem>_<layer><ext>");
  c->add_flag("--close-base", a.close_base, "Close each mesh's bottom ring (a solid)");
  c->add_flag("--no-check", a.no_check, "Skip the CGAL mesh checks");
  c->add_flag("--no-self-intersection", a.no_self_intersection,
              "Skip only CGAL's self-intersection test (the slowest check)");
  c->add_option("--axis-x", a.axis_x, "Drawing x of the vertical axis, m (default: through each "
                "layer's highest point)");
  c->add_option("--symmetry-tolerance", a.symmetry_tolerance, "auto: sides mirrored within this "
                "fraction of the section's extent count as symmetric");
  c->add_option("--chord-tolerance", a.chord_tolerance, "Bulge arcs: largest chord error, m");
  c->add_option("--join-tolerance", a.join_tolerance, "LINE ends closer than this join, m");
  c->add_option("--seed", a.seed, "Random seed of the sampling");
  c->add_option("--threads", a.threads, "Threads (0: all)")->check(CLI::Range(0, 256));
  c->callback([run, &a] { *run = [&a] { return RunFoundation(a); }; });
  c->footer("Example: candi foundation examples/borobudur/foundation.dxf -o foundation.ply "
            "--layers A,B,C,D --mesh foundation.obj");
}

void AddSfm(CLI::App& app, SfmArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("sfm", "Structure from motion with COLMAP: photos to a sparse model "
                               "and a dense workspace (WORKSPACE/dense)");
  c->add_option("images", a.images, "Folder of photos (other files are ignored)")->required();
  c->add_option("-o,--output", a.workspace, "Workspace folder (created)")->required();
  c->add_option("--colmap", a.colmap, "COLMAP executable (default: $CANDI_COLMAP, else colmap)");
  c->add_option("--max-image-size", a.max_image_size, "Longest side in pixels for SIFT and the "
                "dense images")->check(CLI::Range(64, 100000));
  c->add_option("--max-features", a.max_features, "SIFT features per image")
      ->check(CLI::Range(64, 1000000));
  c->add_option("--exhaustive-max-images", a.exhaustive_max_images, "Exhaustive matching up to "
                "this many images, sequential matching above")->check(CLI::Range(2, 1000000));
  c->add_option("--camera-model", a.camera_model, "COLMAP camera model (SIMPLE_RADIAL, OPENCV, ...)");
  c->add_flag("--camera-per-image", a.camera_per_image, "Separate intrinsics per photo (default: "
              "one shared camera)");
  c->add_option("--threads", a.threads, "Threads for feature extraction and matching (-1: all); "
                "COLMAP verifies and maps on one thread, so the model is the same on every run");
  c->add_flag("--overwrite", a.overwrite, "Replace a previous run in the workspace");
  c->callback([run, &a] { *run = [&a] { return RunSfm(a); }; });
  c->footer("Example: candi sfm photos/ -o work --max-image-size 1600");
}

void AddDense(CLI::App& app, DenseArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("dense", "CPU multi-view PatchMatch stereo on a COLMAP dense workspace "
                               "(images/ + sparse/): depth and normal maps (written to stereo/ for "
                               "COLMAP's stereo_fusion), fused into coloured points with normals");
  c->add_option("workspace", a.workspace, "COLMAP dense workspace (e.g. from candi sfm)")->required();
  c->add_option("-o,--output", a.output, "Point file (.ply .las .xyz .pts)")->required();
  c->add_option("--resolution-scale", a.resolution_scale, "Resample images by this factor (0, 1]");
  c->add_option("--iterations", a.iterations, "PatchMatch rounds (propagation + refinement)");
  c->add_option("--window", a.window, "Matching window radius, pixels");
  c->add_option("--views", a.views, "Source views per reference image");
  c->add_option("--min-consistent", a.min_consistent, "Source views that must agree geometrically");
  c->add_option("--min-views", a.min_views, "Fusion: views per point");
  c->add_flag("--no-maps", a.no_maps, "Do not write stereo/{depth,normal}_maps");
  c->add_option("--seed", a.seed, "Random seed");
  c->add_option("--threads", a.threads, "Threads (0: all)")->check(CLI::Range(0, 256));
  c->callback([run, &a] { *run = [&a] { return RunDense(a); }; });
  c->footer("Example: candi dense workspace -o dense.ply --resolution-scale 0.5 --iterations 3");
}

void AddRegister(CLI::App& app, RegisterArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("register", "ICP refinement of MOVING onto FIXED (PCL, local "
                               "coordinates): RMS, overlap, the 4x4 transform; writes MOVING moved");
  c->add_option("moving", a.moving, "Point file to move")->required();
  c->add_option("fixed", a.fixed, "Point file to register onto")->required();
  c->add_option("-o,--output", a.output, "MOVING after the transform (its precision and shift "
                "kept)")->required();
  c->add_option("--max-distance", a.max_distance, "Largest correspondence distance, m");
  c->add_option("--iterations", a.iterations, "Largest number of ICP iterations");
  c->add_option("--method", a.method, "point (point-to-point) or plane (point-to-plane; normals "
                "estimated when FIXED has none)")->check(CLI::IsMember({"point", "plane"}));
  c->add_option("--voxel", a.voxel, "Thin both clouds to this voxel size for the solve, m");
  c->add_option("--transform-out", a.transform_out, "Write the transform and figures as JSON");
  c->add_option("--initial", a.initial, "Initial transform (JSON as --transform-out writes)");
  c->callback([run, &a] { *run = [&a] { return RunRegister(a); }; });
  c->footer("Example: candi register scan2.las scan1.las -o scan2_reg.las --max-distance 0.2 "
            "--transform-out t.json");
}

void AddClean(CLI::App& app, CleanArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("clean", "Statistical outlier removal (PCL) and voxel thinning "
                               "(one real point per voxel); every field kept");
  c->add_option("input", a.input, "Input point file")->required();
  c->add_option("-o,--output", a.output, "Output point file")->required();
  c->add_option("--sor-k", a.sor_k, "Outlier removal: neighbours averaged");
  c->add_option("--sor-std", a.sor_std, "Outlier removal: threshold in standard deviations");
  c->add_flag("--no-sor", a.no_sor, "Skip outlier removal");
  c->add_option("--voxel", a.voxel, "Keep the point nearest each voxel's centre, voxel side m");
  c->callback([run, &a] { *run = [&a] { return RunClean(a); }; });
  c->footer("Example: candi clean dense.ply -o dense_clean.ply --voxel 0.01");
}

void AddGeoref(CLI::App& app, GeorefArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("georef", "Georeference with total-station targets: robust "
                               "similarity (Ceres), residuals per target, RMSE of control and "
                               "check targets; per chunk, ties chunks into one frame");
  c->add_option("input", a.input, "Point file, or a COLMAP sparse model folder")->required();
  c->add_option("--targets", a.targets, "Targets CSV: name,E,N,H,role,accuracy[,x,y,z]")->required();
  c->add_option("-o,--output", a.output, "Output point file (or folder, for a model); also "
                "writes OUT.georef.json")->required();
  c->add_option("--model", a.model, "COLMAP sparse model whose images the picks are in");
  c->add_option("--picks", a.picks, "Picks CSV: name,image,u,v (pixels, undistorted images)");
  c->add_option("--loss", a.loss, "Robust loss: huber, cauchy or none")
      ->check(CLI::IsMember({"none", "huber", "cauchy"}));
  c->add_option("--loss-scale", a.loss_scale, "Robust loss scale, m")->check(CLI::PositiveNumber);
  c->add_option("--outlier-threshold", a.outlier_threshold, "Flag residuals above this, m "
                "(default: 4 x max(robust sigma, target accuracy))")->check(CLI::NonNegativeNumber);
  c->add_flag("--rigid", a.rigid, "Rigid fit (scale 1)");
  c->add_option("--crs", a.crs, "CRS of the survey frame (e.g. EPSG:32749), stated in OUT");
  c->add_option("--targets-crs", a.targets_crs, "CRS the targets are given in (e.g. EPSG:4979 for "
                "GNSS); transformed into --crs with PROJ before the fit");
  c->callback([run, &a] { *run = [&a] { return RunGeoref(a); }; });
  c->footer("Example: candi georef chunk1.ply --targets targets.csv -o chunk1_utm.ply");
}

void AddColorCorrect(CLI::App& app, ColorCorrectArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("colorcorrect", "Colour-card correction: a 3x4 matrix in linear RGB "
                               "from the card's patches, applied to a PNG or point colours; "
                               "CIEDE2000 before and after");
  c->add_option("input", a.input, "PNG image or point file with colours")->required();
  c->add_option("-o,--output", a.output, "Corrected output (same kind); also OUT.colorcorrect.json")
      ->required();
  auto* patches = c->add_option("--patches", a.patches, "CSV: patch,measured_r,measured_g,"
                                "measured_b,reference_r,reference_g,reference_b (0..255)");
  auto* card = c->add_option("--card", a.card, "Photo of the colour card (8-bit PNG)");
  auto* corners = c->add_option("--corners", a.corners, "CSV: patch,x0,y0,...,x3,y3,reference_r,"
                                "reference_g,reference_b (corners in pixels, around the patch)");
  patches->excludes(card)->excludes(corners);
  card->needs(corners);
  corners->needs(card);
  c->add_option("--outlier-delta-e", a.outlier_delta_e, "A patch predicted worse than this "
                "(CIEDE2000) may be left out")->check(CLI::PositiveNumber);
  c->add_option("--max-outliers", a.max_outliers, "Patches that may be left out")
      ->check(CLI::Range(0, 100));
  c->callback([run, &a] { *run = [&a] { return RunColorCorrect(a); }; });
  c->footer("Example: candi colorcorrect photo.png -o photo_corrected.png --patches card.csv");
}

// `candi --help` lists the commands in groups along a user's path, not alphabetically. CLI11 prints
// the groups in the order their first command was added and a group's commands in the order they
// were added, so RunCli adds them in this order; GroupCommands checks that it did.
const std::vector<std::pair<std::string, std::vector<std::string>>>& CommandGroups() {
  static const std::vector<std::pair<std::string, std::vector<std::string>>> groups = {
      {"Inspect and convert", {"info", "convert"}},
      {"Digitize",
       {"sfm", "dense", "georef", "register", "clean", "colorcorrect", "foundation", "relief"}},
      {"Assemble", {"build", "pack"}},
      {"Look", {"render", "view", "section"}},
      {"Other", {"opacity", "demo", "bench"}},
  };
  return groups;
}

// Puts every top-level command in its group; a command missing from CommandGroups(), or added out
// of its order, is a programming error (caught by any test that runs candi).
void GroupCommands(CLI::App& app) {
  std::vector<std::string> expected;
  for (const auto& [group, names] : CommandGroups()) {
    for (const std::string& name : names) {
      app.get_subcommand(name)->group(group);
      expected.push_back(name);
    }
  }
  std::vector<std::string> added;
  for (const CLI::App* c : app.get_subcommands({})) added.push_back(c->get_name());
  if (added != expected) {
    throw std::logic_error("cli.cc: the commands are not added in the order of CommandGroups(), "
                           "or one is missing from it");
  }
}

}  // namespace

int RunCli(int argc, char** argv) {
  // Named, so that the usage lines say `candi`, not the path the executable was called by.
  CLI::App app{"candi: heritage records (photos, CAD sections, old photos) to one point archive, "
               "rendered see-through with stochastic point-based rendering", "candi"};
  app.set_version_flag("--version", std::string("candi ") + kVersion);
  app.require_subcommand(1);
  int verbose = 0;
  bool quiet = false;
  app.add_flag("-v,--verbose", verbose, "More log output (debug)");
  app.add_flag("-q,--quiet", quiet, "Only warnings and errors");
  app.footer("Exit codes: 0 ok, 1 usage, 2 bad input, 3 internal error.\n"
             "Run `candi <command> --help` for a command's options.");
  std::function<int()> run;
  // Inspect and convert.
  InfoArgs info;
  AddInfo(app, info, &run);
  ConvertArgs convert;
  AddConvert(app, convert, &run);
  // Digitize.
  SfmArgs sfm;
  AddSfm(app, sfm, &run);
  DenseArgs dense;
  AddDense(app, dense, &run);
  GeorefArgs georef;
  AddGeoref(app, georef, &run);
  RegisterArgs register_args;
  AddRegister(app, register_args, &run);
  CleanArgs clean;
  AddClean(app, clean, &run);
  ColorCorrectArgs colorcorrect;
  AddColorCorrect(app, colorcorrect, &run);
  FoundationArgs foundation;
  AddFoundation(app, foundation, &run);
  ReliefArgs relief;
  AddRelief(app, relief, &run);
  // Assemble.
  BuildArgs build;
  AddBuild(app, build, &run);
  PackArgs pack;
  AddPack(app, pack, &run);
  // Look.
  RenderArgs render;
  AddRender(app, render, &run);
  ViewArgs view;
  AddView(app, view, &run);
  SectionArgs section;
  AddSection(app, section, &run);
  // Other.
  OpacityArgs opacity;
  AddOpacity(app, opacity, &run);
  DemoArgs demo;
  AddDemo(app, demo, &run);
  BenchArgs bench;
  AddBench(app, bench, &run);
  BenchScaleArgs bench_scale;
  AddBenchScale(app, bench_scale, &run);
  BenchViewArgs bench_view;
  AddBenchView(app, bench_view, &run);
  BenchSectionArgs bench_section;
  AddBenchSection(app, bench_section, &run);
  AddBenchRelief(app, relief.bench, &run);  // its arguments live with relief's
  GroupCommands(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    app.exit(e);
    return kUsage;
  }
  SetupLogging(quiet ? -1 : verbose);
  SetConsoleProgressEnabled(!quiet);
  return run ? run() : kUsage;
}

}  // namespace candi::app

// The `candi` command line: every subcommand's options, in one translation unit (CLI11 is heavy).
#include <CLI/CLI.hpp>

#include "apps/commands.h"
#include "apps/logging.h"
#include "core/progress.h"
#include "core/version.h"

namespace candi::app {

namespace {

void AddInfo(CLI::App& app, InfoArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("info", "Print a point file's count, bounds (world), fields, format and shift");
  c->add_option("file", a.input, "Point file (.ply .las .xyz .txt .pts)")->required();
  c->add_option("--columns", a.columns, "XYZ/PTS column spec, e.g. x,y,z,r,g,b");
  c->add_flag("--json", a.json, "Print JSON instead of text");
  c->add_flag("--no-scan", a.no_scan, "Header only: do not read the points (bounds from the header)");
  c->callback([run, &a] { *run = [&a] { return RunInfo(a); }; });
  c->footer("Example: candi info site.las");
}

void AddConvert(CLI::App& app, ConvertArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("convert", "Convert between PLY, LAS, XYZ and PTS, streaming");
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
  c->callback([run, &a] { *run = [&a] { return RunConvert(a); }; });
  c->footer("Example: candi convert scan.las scan.ply --shift auto");
}

void AddDemo(CLI::App& app, DemoArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("demo", "Build and render the bundled example");
  c->add_option("-o,--output", a.output_dir, "Output folder");
  c->add_option("--width", a.width, "Image width in pixels")->check(CLI::Range(16, 16384));
  c->add_option("--height", a.height, "Image height in pixels")->check(CLI::Range(16, 16384));
  c->add_option("--seed", a.seed, "Random seed");
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

void AddRender(CLI::App& app, RenderArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("render", "Render point files see-through with SPBR (stochastic "
                                         "point-based rendering), merged into one image");
  c->add_option("inputs", a.inputs, "Point files (.ply .las .xyz .pts)")->required();
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
  c->add_option("--memory-budget", a.memory_mb, "Stream mode: MB of z-buffers resident per pass");
  c->add_option("--columns", a.columns, "XYZ/PTS column spec");
  c->callback([run, &a] { *run = [&a] { return RunRender(a); }; });
  c->footer("Example: candi render building.ply foundation.ply -o site.png -L 100 --alpha 0.3,0.8");
}

void AddBench(CLI::App& app, BenchArgs& a, std::function<int()>* run) {
  auto* c = app.add_subcommand("bench", "Benchmarks: `candi bench render` prints SPBR accuracy vs "
                                        "time for L = 1 ... 1024");
  c->add_option("what", a.what, "What to measure: render")->check(CLI::IsMember({"render"}));
  c->add_option("--points", a.points, "Points in the generated scene");
  c->add_option("--width", a.width, "Image width")->check(CLI::Range(16, 8192));
  c->add_option("--height", a.height, "Image height")->check(CLI::Range(16, 8192));
  c->add_option("--threads", a.threads, "Threads (0: all)")->check(CLI::Range(0, 256));
  c->callback([run, &a] { *run = [&a] { return RunBench(a); }; });
  c->footer("Example: candi bench render --points 1000000");
}

}  // namespace

int RunCli(int argc, char** argv) {
  CLI::App app{"candi: heritage records (photos, CAD sections, old photos) to one point archive, "
               "rendered see-through with stochastic point-based rendering"};
  app.set_version_flag("--version", std::string("candi ") + kVersion);
  app.require_subcommand(1);
  int verbose = 0;
  bool quiet = false;
  app.add_flag("-v,--verbose", verbose, "More log output (debug)");
  app.add_flag("-q,--quiet", quiet, "Only warnings and errors");
  app.footer("Exit codes: 0 ok, 1 usage, 2 bad input, 3 internal error.\n"
             "Run `candi <command> --help` for a command's options.");
  std::function<int()> run;
  InfoArgs info;
  ConvertArgs convert;
  DemoArgs demo;
  AddInfo(app, info, &run);
  AddConvert(app, convert, &run);
  AddDemo(app, demo, &run);
  OpacityArgs opacity;
  AddOpacity(app, opacity, &run);
  RenderArgs render;
  AddRender(app, render, &run);
  BenchArgs bench;
  AddBench(app, bench, &run);
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

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

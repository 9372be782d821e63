// The `candi` subcommands: plain argument structs (filled by cli.cc, the only CLI11 unit) and
// their entry points. Each Run* returns the process exit code (see ExitCode) and throws
// InputError for bad input, std::invalid_argument for bad option values.
#pragma once

#include <string>
#include <vector>

namespace candi::app {

enum ExitCode : int { kOk = 0, kUsage = 1, kBadInput = 2, kInternal = 3 };

struct GlobalArgs {
  int verbosity = 0;  // -v: debug logging; -q: warnings only (-1)
};

struct InfoArgs {
  std::string input;
  std::string columns;   // XYZ/PTS column spec
  bool json = false;     // machine-readable output
  bool no_scan = false;  // header only: skip the pass over the points
};
int RunInfo(const InfoArgs& args);

struct ConvertArgs {
  std::string input, output;
  std::string shift;        // "" (keep the input's), "auto", "none" or "x,y,z"
  std::string columns;      // input XYZ/PTS column spec
  std::string out_columns;  // output XYZ/PTS column spec
  std::string ply_encoding = "binary";  // binary | binary_be | ascii
  std::string precision = "auto";       // auto | float | double
  std::string las_scale;                // "s" or "sx,sy,sz"
  int las_format = -1;
  int las_version = -1;                 // minor version: 2, 3, 4
};
int RunConvert(const ConvertArgs& args);

struct DemoArgs {
  std::string output_dir = "demo_out";
  int width = 1024, height = 768;
  unsigned long long seed = 1;
};
int RunDemo(const DemoArgs& args);

}  // namespace candi::app

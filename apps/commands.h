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

struct OpacityArgs {
  std::string input, output;
  double alpha = -1;            // target opacity [0, 1] (required)
  int repeat_level = 0;         // L >= 1 (required)
  int image_size = 0;           // pixels across the largest extent; exactly one of this and
  double pixel_size = 0;        // the pixel footprint's side in metres
  unsigned long long seed = 1;
  int neighbours = 32;          // target neighbours for the automatic density radius
  double radius = 0;            // density radius in metres; 0 = automatic
  std::string method = "kdtree";  // kdtree | voxel
  int threads = 0;              // 0 = all available
};
int RunOpacity(const OpacityArgs& args);

struct RenderArgs {
  std::vector<std::string> inputs;
  std::string output;                 // 8-bit PNG
  std::string output16;               // optional 16-bit PNG (analysis)
  int repeat_level = 100;             // L
  unsigned long long seed = 1;
  std::string size = "1024x768";      // WxH (overrides a view's size when given explicitly)
  bool size_given = false;
  std::string view, save_view;        // JSON views (world coordinates)
  std::string background = "0,0,0";  // r,g,b
  std::string brightness = "auto";    // auto | none | a gain >= 0
  std::vector<double> alpha;          // per input (or one for all): opacity control
  bool opaque = false;                // L = 1, multiplicities ignored
  int threads = 0;
  double point_size = 1.0;
  int preview = 0;                    // > 0: only the first k ensembles
  std::string mode = "auto";          // auto | memory | stream
  double memory_mb = 1024;            // stream mode: z-buffers resident per pass
  std::string columns;                // XYZ/PTS inputs
};
int RunRender(const RenderArgs& args);

struct BenchArgs {
  std::string what = "render";        // render
  unsigned long long points = 1000000;
  int width = 256, height = 256;
  int threads = 1;
};
int RunBench(const BenchArgs& args);

}  // namespace candi::app

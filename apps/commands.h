// The command groups of `candi` (cli.cc adds them in this order) and the commands whose code is
// in one executable only. The commands are split over three executables built from the same
// sources, so that a call loads only the shared libraries it needs (main.cc hands a command over
// to the sibling that has it): `candi-pcl` runs register and clean (PCL), `candi-relief` the
// relief commands but `place`, the demo and `bench relief` (libtorch); `candi` all the others.
// Every executable declares every command (its options and --help); handoff_stubs.cc stands in
// for the run functions an executable does not hold.
#pragma once

#include <string>
#include <vector>

#include "apps/cli.h"
#include "bench/bench.h"
#include "core/field_colour.h"
#include "pipeline/build.h"
#include "pipeline/demo_site.h"
#include "reconstruction/photogrammetry/cleaning.h"
#include "reconstruction/photogrammetry/coarse_alignment.h"
#include "reconstruction/photogrammetry/multi_registration.h"
#include "reconstruction/photogrammetry/registration.h"

namespace candi::apps {

// The point files the commands read and write, as their options' help lists them (the formats
// are io/point_io.h's; COPC is written for a name ending in .copc.laz and read as LAZ).
#define CANDI_POINT_FILES_READ "(.ply .las .laz .e57 .xyz .pts)"
#define CANDI_POINT_FILES_WRITTEN "(.ply .las .laz .copc.laz .e57 .xyz .pts)"

// --copc-memory MB (convert, build, export copc; inspect.cc): the memory a COPC file's records
// may take until it is complete, beyond which they are spilled beside it (0: half this
// machine's). CopcMemoryBytes: its bytes; std::invalid_argument for a negative or NaN value.
void AddCopcMemory(Command& c, double& mb);
uint64_t CopcMemoryBytes(double mb);

void AddInspectCommands(Command& root);   // info, convert, compare (inspect.cc)
void AddDigitizeCommands(Command& root);  // sfm, dense, georef, register, register-scans, clean, colorcorrect, foundation,
                                          // relief (digitize.cc, relief.cc)
void AddReliefCommands(Command& root);    // relief synth|dataset|train|predict|points|eval|place (relief.cc)
void AddAssembleCommands(Command& root);  // build, pack, export (assemble.cc)
void AddLookCommands(Command& root);      // render, view, publish, section (look.cc)
// `candi --help` lists these three under "Other", after the groups above.
void AddOpacity(Command& root);           // opacity (opacity_command.cc: SPBR opacity, by the renderer)
void AddDemo(Command& root);              // demo (assemble.cc: it builds the bundled example)
void AddBenchCommands(Command& root);     // bench and its subcommands (bench_commands.cc)

// --colour-by, --field-range and --field-scale of render, view and pack: points coloured by a
// scalar field (look.cc).
struct FieldArgs {
  std::string field, range, scale = "auto";
};
void AddFieldColouring(Command& c, FieldArgs& f);
// std::invalid_argument for a bad range or scale, or a range or scale without a field.
FieldColouring ParseFieldColouring(const FieldArgs& f);

// candi-pcl (pcl_commands.cc).
struct RegisterArgs {
  std::string moving, fixed, output;
  photogrammetry::RegistrationOptions icp;
  std::string transform_out;         // optional JSON: the 4x4 and the figures
  std::string initial;               // optional JSON: initial fixed_from_moving (same format)
};
int RunRegister(const RegisterArgs& args);

// candi register-scans: many scans into one frame at once (multi_registration.h).
struct RegisterScansArgs {
  std::vector<std::string> scans;     // point files, one scan each
  std::string output_dir;             // the moved scans, registration.json
  photogrammetry::MultiRegistrationOptions options;
  std::string fixed;                  // "0,2": scans held at their start pose
  std::string poses;                  // optional JSON: start poses world_from_scan
  std::string targets;                // optional CSV: targets seen in the scans
  bool coarse = false;                // scans without a start pose: FPFH + RANSAC onto scan 0 first
  photogrammetry::CoarseAlignmentOptions coarse_options;
  std::string format;                 // output extension ("" = each scan's own)
};
int RunRegisterScans(const RegisterScansArgs& args);

struct CleanArgs {
  std::string input, output;
  photogrammetry::CleanOptions clean;
};
int RunClean(const CleanArgs& args);

// candi-relief (demo_command.cc, relief_commands.cc).
struct DemoArgs {
  std::string output_dir = "demo_out";
  pipeline::DemoSiteOptions site;
};
int RunDemo(const DemoArgs& args);
// The layer table and the totals `candi build` and `candi demo` print (assemble.cc).
void PrintBuildSummary(const std::string& output, const pipeline::BuildSummary& summary);
int RunBenchRelief(const bench::ReliefBenchOptions& options);

}  // namespace candi::apps

// The commands of `candi`, one function each that declares it (cli.cc adds them in the order
// `candi --help` lists them), in files named by their subject, and the commands whose code is in
// one executable only. The commands are split over three executables built from the same
// sources, so that a call loads only the shared libraries it needs (main.cc hands a command over
// to the sibling that has it): `candi-pcl` runs register, register-scans and clean (PCL),
// `candi-relief` the relief commands but `place`, the demo and `bench relief` (libtorch); `candi`
// all the others. Every executable declares every command (its options and --help);
// handoff_stubs.cc stands in for the run functions an executable does not hold.
#pragma once

#include <string>

#include "apps/cli.h"
#include "bench/bench.h"
#include "pipeline/build.h"
#include "pipeline/demo_site.h"
#include "pipeline/scan_registration.h"
#include "reconstruction/photogrammetry/registration/cleaning.h"

namespace candi::apps {

// The point files the commands read and write, as their options' help lists them (the formats
// are io/point_io.h's; COPC is written for a name ending in .copc.laz and read as LAZ).
#define CANDI_POINT_FILES_READ "(.ply .las .laz .e57 .xyz .pts)"
#define CANDI_POINT_FILES_WRITTEN "(.ply .las .laz .copc.laz .e57 .xyz .pts)"

// points.cc: a point file's figures, conversion, packing into a render archive, a build's export.
void AddInfo(Command& root);
void AddConvert(Command& root);
void AddPack(Command& root);
void AddExport(Command& root);
// compare.cc: the deviation of one cloud from another, or from a mesh.
void AddCompare(Command& root);
// photogrammetry.cc: the building from photos (sfm, dense, georef), colour-card correction, and a
// synthetic photo campaign with its truth.
void AddSfm(Command& root);
void AddDense(Command& root);
void AddGeoref(Command& root);
void AddColorCorrect(Command& root);
void AddCampaign(Command& root);
// register.cc: scans registered and cleaned (run by register_run.cc, in candi-pcl).
void AddRegister(Command& root);
void AddRegisterScans(Command& root);
void AddClean(Command& root);
// foundation.cc: the foundation from CAD sections.
void AddFoundation(Command& root);
// relief.cc: relief synth|dataset|train|predict|points|eval|place (run by relief_network.cc, in
// candi-relief, and relief_place.cc).
void AddReliefCommands(Command& root);
// build.cc: a scene file's archive, and the bundled example's (run by demo.cc, in candi-relief).
void AddBuild(Command& root);
void AddDemo(Command& root);
// render.cc: see-through images, sections, SPBR opacity.
void AddRender(Command& root);
void AddSection(Command& root);
void AddOpacity(Command& root);
// view.cc: the browser viewer and the static site.
void AddView(Command& root);
void AddPublish(Command& root);
// bench.cc: bench and its subcommands.
void AddBench(Command& root);

// candi-pcl (register_run.cc).
struct RegisterArgs {
  std::string moving, fixed, output;
  pipeline::RegisterPairOptions options;  // ICP, the initial transform, the transform's JSON
};
int RunRegister(const RegisterArgs& args);

// candi register-scans: many scans into one frame at once (pipeline/scan_registration.h).
struct RegisterScansArgs {
  std::vector<std::string> scans;     // point files, one scan each (an E57 file: each of its scans)
  std::string output_dir;             // the moved scans, registration.json
  pipeline::RegisterScansOptions options;
};
int RunRegisterScans(const RegisterScansArgs& args);

struct CleanArgs {
  std::string input, output;
  photogrammetry::CleanOptions clean;
};
int RunClean(const CleanArgs& args);

// candi-relief (demo.cc, relief_network.cc).
struct DemoArgs {
  std::string output_dir = "demo_out";
  pipeline::DemoSiteOptions site;
};
int RunDemo(const DemoArgs& args);
// The layer table and the totals `candi build` and `candi demo` print (build.cc).
void PrintBuildSummary(const std::string& output, const pipeline::BuildSummary& summary);
int RunBenchRelief(const bench::ReliefBenchOptions& options);

}  // namespace candi::apps

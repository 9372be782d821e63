// candi clean IN -o OUT: statistical outlier removal and voxel thinning
// (reconstruction/photogrammetry/cleaning.h); prints the counts removed per step. Every attribute
// of the kept points, the shift and the position precision are kept.
#include <chrono>
#include <cstdio>
#include <string>

#include "apps/commands.h"
#include "apps/output_folder.h"
#include "core/progress.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/cleaning.h"

namespace candi::app {

namespace {

photogrammetry::CleanOptions Options(const CleanArgs& a) {
  photogrammetry::CleanOptions o;
  o.sor = !a.no_sor;
  o.sor_neighbours = a.sor_k;
  o.sor_std_multiplier = a.sor_std;
  o.voxel = a.voxel;
  o.Check();
  return o;
}

void PrintRow(const char* what, uint64_t count, uint64_t input) {
  std::printf("%-28s %12llu  %6.2f %%\n", what, static_cast<unsigned long long>(count),
              input ? 100.0 * static_cast<double>(count) / static_cast<double>(input) : 0.0);
}

}  // namespace

int RunClean(const CleanArgs& args) {
  const photogrammetry::CleanOptions options = Options(args);  // std::invalid_argument, exit 1
  io::OutputPointFormat(args.output);
  CheckOutputFolder(args.output);
  const auto start = std::chrono::steady_clock::now();
  const PointCloud cloud = io::ReadPointCloud(args.input);
  photogrammetry::CleanResult result;
  {
    ConsoleProgressOptions po;
    po.unit = "steps";
    ConsoleProgress progress("clean", po);
    result = photogrammetry::CleanPointCloud(options, cloud, progress.Callback());
  }
  io::WritePointCloud(args.output, result.cloud);
  const photogrammetry::CleanSummary& s = result.summary;
  std::printf("input %s\n", args.input.c_str());
  PrintRow("points in", s.input, s.input);
  PrintRow("removed: not finite", s.non_finite, s.input);
  if (options.sor) {
    char label[64];
    std::snprintf(label, sizeof(label), "removed: outliers (k %d, %gs)", options.sor_neighbours,
                  options.sor_std_multiplier);
    PrintRow(label, s.outliers, s.input);
  }
  if (options.voxel > 0) {
    char label[64];
    std::snprintf(label, sizeof(label), "removed: voxel %g m", options.voxel);
    PrintRow(label, s.thinned, s.input);
  }
  PrintRow("points out", s.output, s.input);
  std::printf("wrote %s, time %.2f s\n", args.output.c_str(),
              std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return kOk;
}

}  // namespace candi::app

// candi dense WORKSPACE -o OUT: CPU PatchMatch stereo (reconstruction/photogrammetry/patch_match.h)
// on a COLMAP dense workspace, depth/normal maps written back as COLMAP arrays, own fusion
// (fusion.h) into coloured points with normals.
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "core/log.h"
#include "core/progress.h"
#include "io/point_io.h"
#include "reconstruction/photogrammetry/dense_workspace.h"
#include "reconstruction/photogrammetry/fusion.h"
#include "reconstruction/photogrammetry/patch_match.h"

namespace candi::app {

namespace pg = candi::photogrammetry;

namespace {
double Since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

int RunDense(const DenseArgs& args) {
  pg::PatchMatchOptions options;
  options.resolution_scale = args.resolution_scale;
  options.iterations = args.iterations;
  options.window_radius = args.window;
  options.window_step = args.window >= 3 ? 2 : 1;
  options.num_source_views = args.views;
  options.min_consistent_views = args.min_consistent;
  options.seed = args.seed;
  options.threads = args.threads;
  options.Check();
  pg::FusionOptions fusion;
  fusion.min_views = args.min_views;
  fusion.Check();
  io::OutputPointFormat(args.output);  // an unknown extension fails before the work

  const auto t0 = std::chrono::steady_clock::now();
  const pg::StereoInput input = pg::ReadDenseWorkspace(args.workspace);
  std::printf("workspace %s: %zu images, %zu sparse points\n", args.workspace.c_str(),
              input.images.size(), input.sparse_points.size());
  pg::PatchMatchResult stereo;
  {
    ConsoleProgressOptions p;
    p.unit = "pixel sweeps";
    ConsoleProgress progress("dense: PatchMatch", p);
    stereo = pg::RunPatchMatch(options, input, progress.Callback());
  }
  const double stereo_s = Since(t0);
  if (!args.no_maps) {
    std::vector<std::string> names;
    for (const pg::StereoImage& image : input.images) names.push_back(image.name);
    pg::WriteDepthNormalMaps(stereo.maps, names, args.workspace);
  }
  PointCloud cloud;
  {
    ConsoleProgressOptions p;
    p.unit = "pixels";
    ConsoleProgress progress("dense: fusion", p);
    cloud = pg::FuseDepthMaps(fusion, stereo.maps, progress.Callback());
  }
  cloud.meta.comments.push_back("candi dense " + args.workspace);
  io::WritePointCloud(args.output, cloud);
  const double total_s = Since(t0);
  std::printf("depth maps: %llu of %llu pixels valid (%.1f %%)\n",
              static_cast<unsigned long long>(stereo.valid_pixels),
              static_cast<unsigned long long>(stereo.total_pixels),
              stereo.total_pixels ? 100.0 * stereo.valid_pixels / stereo.total_pixels : 0.0);
  std::printf("fused points: %zu -> %s\n", cloud.size(), args.output.c_str());
  std::printf("time: %.2f s (reading and PatchMatch %.2f s), %.0f points/s\n", total_s, stereo_s,
              total_s > 0 ? cloud.size() / total_s : 0.0);
  if (cloud.empty()) LogWarning("dense: no points (textureless images, no overlap, or too strict filters)");
  return kOk;
}

}  // namespace candi::app

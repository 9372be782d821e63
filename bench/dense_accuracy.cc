// candi bench dense: PatchMatch accuracy and completeness against time on the synthetic scene
// (reconstruction/photogrammetry/scenes/synthetic_views.h), for resolution scale x iterations, then the
// throughput (fused points per second) at --width x --height.
#include <chrono>
#include <cstdio>
#include <vector>

#include "bench/bench.h"
#include "reconstruction/photogrammetry/mvs/fusion.h"
#include "reconstruction/photogrammetry/mvs/patch_match.h"
#include "reconstruction/photogrammetry/scenes/synthetic_views.h"

namespace candi::bench {

namespace pg = candi::photogrammetry;

namespace {

struct DenseRow {
  pg::SyntheticDenseScore score;
  double seconds = 0;
};

DenseRow RunOnce(const std::vector<pg::SyntheticView>& views, double scale, int iterations,
                 int threads) {
  pg::StereoInput input;
  for (const auto& v : views) input.images.push_back({v.name, v.image, v.camera});
  input.sparse_points = pg::SyntheticSparsePoints(views, 16);
  pg::PatchMatchOptions o;
  o.resolution_scale = scale;
  o.iterations = iterations;
  o.threads = threads;
  const auto t0 = std::chrono::steady_clock::now();
  const pg::PatchMatchResult stereo = pg::RunPatchMatch(o, input);
  const PointCloud cloud = pg::FuseDepthMaps(pg::FusionOptions(), stereo.maps);
  DenseRow row;
  row.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::vector<ImageF> depths;
  for (const auto& m : stereo.maps) depths.push_back(m.depth);
  std::vector<Eigen::Vector3d> points;
  for (size_t i = 0; i < cloud.size(); ++i) points.push_back(cloud.WorldPosition(i));
  row.score = pg::ScoreSyntheticDense(views, depths, points);
  return row;
}

void PrintRow(const char* label, double scale, int iterations, const DenseRow& r) {
  std::printf("%-10s %6.2f %6d %10llu %9.1f%% %12.1f%% %10.5f %9.2f %10.0f\n", label, scale,
              iterations, static_cast<unsigned long long>(r.score.points), 100 * r.score.accuracy,
              100 * r.score.completeness, r.score.median_error, r.seconds,
              r.seconds > 0 ? r.score.points / r.seconds : 0.0);
}

}  // namespace

int RunDenseAccuracy(const BenchOptions& args) {
  pg::SyntheticViewsOptions small;
  small.views = 6;
  small.width = 320;
  small.height = 240;
  const auto views = pg::RenderSyntheticViews(small);
  std::printf("PatchMatch on the synthetic scene: accuracy = points within 1 %% of the depth, "
              "completeness = pixels with a depth within 1 %%; %d thread(s)\n", args.threads);
  std::printf("%-10s %6s %6s %10s %10s %13s %10s %9s %10s\n", "scene", "scale", "iters", "points",
              "accuracy", "completeness", "median", "seconds", "points/s");
  for (double scale : {0.5, 1.0})
    for (int iterations : {1, 2, 3, 5}) PrintRow("6x320x240", scale, iterations, RunOnce(views, scale, iterations, args.threads));
  pg::SyntheticViewsOptions big;
  big.views = 8;
  big.width = args.width;
  big.height = args.height;
  big.supersample = 2;
  const auto large = pg::RenderSyntheticViews(big);
  char label[32];
  std::snprintf(label, sizeof(label), "8x%dx%d", args.width, args.height);
  PrintRow(label, 1.0, 3, RunOnce(large, 1.0, 3, args.threads));
  return 0;
}

}  // namespace candi::bench

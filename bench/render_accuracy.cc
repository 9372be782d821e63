// candi bench render: SPBR accuracy against time. A scene of four overlapping sheets is set to
// opacity 0.5 per sheet (point-number adjustment) for each repeat level L, rendered with SPBR and
// compared with the exact depth-sorted blending of the same points: RMSE (grey levels) falls as
// 1/sqrt(L) while the time grows with the copies drawn.
#include <chrono>
#include <cstdio>

#include "bench/bench.h"
#include "core/check.h"
#include "render/reference.h"
#include "render/spbr.h"
#include "render/splat_cloud.h"
#include "render/synthetic_scene.h"
#include "sampling/opacity.h"

namespace candi::bench {

void BenchOptions::Check() const {
  CANDI_CHECK_OPTION(what == "render" || what == "foundation" || what == "dense", what, "render, foundation or dense");
  CANDI_CHECK_OPTION_GT(points, 0);
  CANDI_CHECK_OPTION_IN(width, 16, 8192);
  CANDI_CHECK_OPTION_IN(height, 16, 8192);
  CANDI_CHECK_OPTION_IN(threads, 0, 256);
  CANDI_CHECK_OPTION_IN(scale, 0.05, 1.0);
  CANDI_CHECK_OPTION_IN(iterations, 1, 50);
  CANDI_CHECK_OPTION_IN(campaign_size, 64, 8192);
  CANDI_CHECK_OPTION_IN(views, 1, 32);
  CANDI_CHECK_OPTION_GE(grid_at, 0);
}

int RunBench(const BenchOptions& args) {
  args.Check();
  if (args.what == "foundation") return RunFoundationAccuracy();
  if (args.what == "dense" && !args.campaign.empty()) return RunDenseCampaign(args);
  if (args.what == "dense") return args.data.empty() ? RunDenseAccuracy(args) : RunDenseSceaux(args);
  return RunRenderAccuracy(args);
}

int RunRenderAccuracy(const BenchOptions& args) {
  const PointCloud scene = render::LayeredSheets(args.points, 4, 7);
  std::printf("SPBR accuracy vs time: %llu points (4 sheets, alpha 0.5 each), %dx%d, %d thread(s)\n",
              static_cast<unsigned long long>(args.points), args.width, args.height, args.threads);
  std::printf("%6s %12s %12s %12s %12s %10s\n", "L", "copies", "opacity ms", "build ms", "render ms", "RMSE");
  for (int L : {1, 4, 16, 64, 256, 1024}) {
    sampling::OpacityOptions opacity;
    opacity.alpha = 0.5;
    opacity.spbr.repeat_level = L;
    opacity.image_size = std::max(args.width, args.height);
    opacity.density.threads = args.threads;
    auto t0 = std::chrono::steady_clock::now();
    const PointCloud adjusted = sampling::AdjustOpacity(opacity, scene).cloud;
    const double opacity_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    render::SplatCloudOptions build;
    build.spbr.repeat_level = L;
    t0 = std::chrono::steady_clock::now();
    const render::SplatCloud splats = render::BuildSplatCloud(build, {&adjusted});
    const double build_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const render::Camera camera = render::ObliqueView(splats.bounds, args.width, args.height);
    render::SpbrOptions options;
    options.threads = args.threads;
    const render::SpbrResult result = render::RenderSpbr(options, camera, splats);
    render::ReferenceOptions ref;
    ref.spbr.repeat_level = L;
    const ImageF exact = render::RenderSortedBlend(ref, camera, splats.frame, {&adjusted});
    const double rmse = render::Rmse(render::AverageImage(result, {0, 0, 0}), exact);
    std::printf("%6d %12llu %12.1f %12.1f %12.1f %10.2f\n", L, static_cast<unsigned long long>(result.copies),
                opacity_ms, build_ms, result.milliseconds, rmse);
  }
  return 0;
}

}  // namespace candi::bench

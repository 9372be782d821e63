// Relief throughput: a 3200x1024 depth map to 3,276,800 metric points, and the tile blending of
// a 3200x1024 image (identity predictor: the cost of tiling itself). The network's accuracy vs
// time table is `candi bench relief`.
#include <benchmark/benchmark.h>

#include "reconstruction/relief/relief_points.h"
#include "reconstruction/relief/relief_tiles.h"

namespace {

candi::ImageF Photo(int w, int h) {
  candi::ImageF im(w, h, 1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) im.at(x, y) = static_cast<float>((x * 7 + y * 13) % 255) / 255.0f;
  }
  return im;
}

void BM_DepthToPoints(benchmark::State& state) {
  const candi::ImageF photo = Photo(3200, 1024), depth = Photo(3200, 1024);
  for (auto _ : state) {
    benchmark::DoNotOptimize(candi::relief::DepthToPoints({}, photo, depth).size());
  }
  state.SetItemsProcessed(state.iterations() * 3200 * 1024);
}
BENCHMARK(BM_DepthToPoints)->Unit(benchmark::kMillisecond);

void BM_TileBlending(benchmark::State& state) {
  const candi::ImageF photo = Photo(3200, 1024);
  candi::relief::TileOptions o;
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        candi::relief::PredictTiled(o, photo, [](const candi::ImageF& t) { return t; }).width());
  }
  state.SetItemsProcessed(state.iterations() * 3200 * 1024);
}
BENCHMARK(BM_TileBlending)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();

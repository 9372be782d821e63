// Point-file throughput: binary PLY (float and double positions) and LAS (point format 3), read
// and write, 10^7 points with colour, from and to the page cache. Prints Google Benchmark's
// table with points/s; medians of 5 repetitions. Target (issue 2): read >= 50 M points/s,
// write >= 30 M points/s. Set CANDI_BENCH_POINTS to change the size.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/point_io.h"
#include "core/rng.h"

namespace {

using namespace candi;

size_t Points() {
  const char* env = std::getenv("CANDI_BENCH_POINTS");
  return env ? std::strtoull(env, nullptr, 10) : 10000000;
}

std::string Dir() {
  static const std::string dir = [] {
    const char* tmp = std::getenv("TMPDIR");
    std::string d = std::string(tmp ? tmp : "/tmp") + "/candi-io-bench";
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

const PointCloud& Cloud(ScalarType position_type) {
  static PointCloud clouds[2];
  PointCloud& c = clouds[position_type == ScalarType::kFloat64];
  if (c.empty()) {
    c.schema.colors = true;
    c.schema.position_type = position_type;
    c.SetSchema(c.schema);
    c.Resize(Points());
    Rng rng(1);
    for (size_t i = 0; i < c.size(); ++i) {
      c.positions[i] = Eigen::Vector3d(rng.Uniform(0, 100), rng.Uniform(0, 100), rng.Uniform(0, 30));
      if (position_type == ScalarType::kFloat32) c.positions[i] = c.positions[i].cast<float>().cast<double>();
      c.colors[i] = {static_cast<uint8_t>(i), static_cast<uint8_t>(i >> 8), static_cast<uint8_t>(i >> 16)};
    }
  }
  return c;
}

struct Case {
  const char* file;
  ScalarType type;
};
const Case kCases[] = {{"float.ply", ScalarType::kFloat32}, {"double.ply", ScalarType::kFloat64},
                       {"fmt3.las", ScalarType::kFloat64}};

void BM_Write(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  const PointCloud& cloud = Cloud(c.type);
  for (auto _ : state) WritePointCloud(Dir() + "/" + c.file, cloud);
  state.SetItemsProcessed(state.iterations() * cloud.size());
  state.SetLabel(c.file);
}

// range(1) = 0: every field (lossless); 1: geometry and colour only (PointReadOptions::scalar_fields).
void BM_Read(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  const std::string path = Dir() + "/" + c.file;
  if (!std::filesystem::exists(path)) WritePointCloud(path, Cloud(c.type));
  PointReadOptions options;
  options.scalar_fields = state.range(1) == 0;
  size_t n = 0;
  for (auto _ : state) {
    auto reader = OpenPointReader(path, options);
    PointCloud chunk;
    n = 0;
    while (size_t got = reader->Read(1 << 16, &chunk)) n += got;
    benchmark::DoNotOptimize(chunk.positions.data());
  }
  state.SetItemsProcessed(state.iterations() * n);
  state.SetLabel(std::string(c.file) + (options.scalar_fields ? "" : " xyz+rgb only"));
}

BENCHMARK(BM_Write)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->UseRealTime()
    ->Repetitions(5)->ReportAggregatesOnly(true)->Iterations(1);
BENCHMARK(BM_Read)->ArgsProduct({{0, 1, 2}, {0}})->Args({2, 1})->Unit(benchmark::kMillisecond)->UseRealTime()
    ->Repetitions(5)->ReportAggregatesOnly(true)->Iterations(1);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  std::filesystem::remove_all(Dir());
  return 0;
}

// SPBR benchmarks. Prints:
//  1. splat throughput, one thread and two, 1024^2, L = 1, 10, 100 (10^7 points);
//  2. per-ensemble overhead (L = 1000 ensembles of ~100 points);
//  3. SPBR vs exact depth-sorted blending vs weighted blended OIT at 10^6 and 10^7 points:
//     milliseconds and RMSE to the exact image;
//  4. the big frame: 1.5 * 10^8 points, L = 100, 1024^2, two threads: seconds, bytes per point.
// Medians of 3 runs. Usage: render_bench [--quick] [--big N] (N points for section 4; 0 skips)
// [--section K]... (only these sections); render_bench --profile N L [R]: R (1) 1024^2 renders
// of N points at L, one thread, their median and the fastest (for profilers).
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "render/reference.h"
#include "render/spbr.h"
#include "render/splat_cloud.h"
#include "render/synthetic_scene.h"

namespace {

using namespace candi;
using namespace candi::render;

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

SplatCloud Build(const PointCloud& cloud, int L, uint64_t seed = 1) {
  SplatCloudOptions o;
  o.spbr.repeat_level = L;
  o.spbr.seed = seed;
  return BuildSplatCloud(o, {&cloud});
}

double CpuMs() {
  timespec t;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return t.tv_sec * 1e3 + t.tv_nsec * 1e-6;
}

// Median wall milliseconds of `runs` renders; *cpu_ms (when given) the median CPU time of the
// calling thread (the one that renders when threads = 1),
// which a busy machine inflates far less than wall time.
double RenderMs(const SplatCloud& splats, const Camera& camera, int threads, int runs = 3,
                double* cpu_ms = nullptr) {
  std::vector<double> ms, cpu;
  SpbrOptions o;
  o.threads = threads;
  for (int r = 0; r < runs; ++r) {
    const double c0 = CpuMs();
    ms.push_back(RenderSpbr(o, camera, splats).milliseconds);
    cpu.push_back(CpuMs() - c0);
  }
  if (cpu_ms) *cpu_ms = Median(cpu);
  return Median(ms);
}

void Throughput(uint64_t n) {
  std::printf("\n1. Splat throughput, %llu points (terraced solid), 1024x1024\n",
              static_cast<unsigned long long>(n));
  std::printf("%6s %12s %12s %14s %14s %16s\n", "L", "ms 1 thr", "ms 2 thr", "Mpts/s 1 thr",
              "Mpts/s 2 thr", "Mpts/s CPU 1 thr");
  const PointCloud cloud = TerracedSolid(n, 1);
  for (int L : {1, 10, 100}) {
    const SplatCloud splats = Build(cloud, L);
    const Camera camera = ObliqueView(splats.bounds, 1024, 1024);
    double cpu1 = 0;
    const double t1 = RenderMs(splats, camera, 1, 3, &cpu1), t2 = RenderMs(splats, camera, 2);
    std::printf("%6d %12.1f %12.1f %14.1f %14.1f %16.1f\n", L, t1, t2, n / t1 / 1e3, n / t2 / 1e3,
                n / cpu1 / 1e3);
  }
}

void EnsembleOverhead() {
  std::printf("\n2. Per-ensemble overhead, 1024x1024, 1000 ensembles of ~100 points\n");
  const PointCloud cloud = TerracedSolid(100000, 2);
  const SplatCloud splats = Build(cloud, 1000);
  const Camera camera = ObliqueView(splats.bounds, 1024, 1024);
  const double t1 = RenderMs(splats, camera, 1);
  std::printf("   %.1f ms for 1000 ensembles: %.3f ms per ensemble (one thread)\n", t1, t1 / 1000);
}

void AgainstReferences(uint64_t n, int L) {
  const PointCloud cloud = LayeredSheets(n, 4, 3);
  const SplatCloud splats = Build(cloud, L);
  const Camera camera = ObliqueView(splats.bounds, 1024, 1024);
  ReferenceOptions ref;
  ref.spbr.repeat_level = L;
  auto t0 = std::chrono::steady_clock::now();
  const ImageF exact = RenderSortedBlend(ref, camera, splats.frame, {&cloud});
  const double exact_ms = 1e3 * Seconds(t0);
  t0 = std::chrono::steady_clock::now();
  const ImageF oit = RenderWeightedOit(ref, camera, splats.frame, {&cloud});
  const double oit_ms = 1e3 * Seconds(t0);
  SpbrOptions o;
  o.threads = 1;
  const SpbrResult r = RenderSpbr(o, camera, splats);
  const ImageF spbr = AverageImage(r, {0, 0, 0});
  std::printf("%10llu %6d %16.1f %10.2f %14.1f %10.2f %12.1f %10.2f\n",
              static_cast<unsigned long long>(n), L, r.milliseconds, Rmse(spbr, exact), oit_ms,
              Rmse(oit, exact), exact_ms, 0.0);
}

void BigFrame(uint64_t n) {
  std::printf("\n4. Big frame: %llu points, L = 100, 1024x1024\n", static_cast<unsigned long long>(n));
  PointCloud cloud = TerracedSolid(n, 4);
  auto t0 = std::chrono::steady_clock::now();
  SplatCloud splats = Build(cloud, 100);
  const double build_s = Seconds(t0);
  cloud = PointCloud();  // the source is not needed for rendering
  const Camera camera = ObliqueView(splats.bounds, 1024, 1024);
  const double t1 = RenderMs(splats, camera, 1), t2 = RenderMs(splats, camera, 2);
  struct rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  std::printf("   build %.1f s; render %.2f s (1 thread), %.2f s (2 threads); SplatCloud %.2f bytes/point;"
              " peak RSS %.2f GiB (includes the build)\n",
              build_s, t1 / 1e3, t2 / 1e3, double(splats.MemoryBytes()) / n,
              usage.ru_maxrss / 1048576.0);
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false;
  uint64_t big = 150000000;
  std::vector<int> sections;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--quick")) quick = true;
    if (!std::strcmp(argv[i], "--big") && i + 1 < argc) big = std::strtoull(argv[++i], nullptr, 10);
    if (!std::strcmp(argv[i], "--section") && i + 1 < argc) sections.push_back(std::atoi(argv[++i]));
  }
  for (int i = 1; i + 2 < argc; ++i) {
    if (!std::strcmp(argv[i], "--profile")) {  // renders for profilers: --profile N L [R]
      const PointCloud cloud = TerracedSolid(std::strtoull(argv[i + 1], nullptr, 10), 1);
      const SplatCloud splats = Build(cloud, std::atoi(argv[i + 2]));
      const Camera camera = ObliqueView(splats.bounds, 1024, 1024);
      const int runs = i + 3 < argc ? std::max(1, std::atoi(argv[i + 3])) : 1;
      std::vector<double> ms;
      for (int r = 0; r < runs; ++r) ms.push_back(RenderMs(splats, camera, 1, 1));
      std::printf("%.1f ms (median of %d; fastest %.1f ms)\n", Median(ms), runs,
                  *std::min_element(ms.begin(), ms.end()));
      return 0;
    }
  }
  auto wanted = [&](int k) { return sections.empty() || std::count(sections.begin(), sections.end(), k) > 0; };
  if (wanted(1)) Throughput(quick ? 1000000 : 10000000);
  if (wanted(2)) EnsembleOverhead();
  if (wanted(3)) {
  std::printf("\n3. SPBR vs references (4 layered sheets, 1024x1024, one thread)\n");
  std::printf("%10s %6s %16s %10s %14s %10s %12s %10s\n", "points", "L", "SPBR ms", "RMSE",
              "WBOIT ms", "RMSE", "sorted ms", "RMSE");
  for (uint64_t n : {uint64_t{1000000}, uint64_t{10000000}}) {
    if (quick && n > 1000000) break;
    AgainstReferences(n, 100);
  }
  }
  if (wanted(4) && !quick && big > 0) BigFrame(big);
  return 0;
}

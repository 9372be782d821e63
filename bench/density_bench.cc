// Surface density: accuracy vs time of the kd-tree and voxel estimates (sampling/density.h).
//
// Data: 10^6 points uniform on a sphere of radius 5 m (true density N / (4 pi R^2), every
// orientation, no border). A ball of radius r centred on the sphere cuts a cap of area exactly
// pi r^2 (Archimedes), so the kd-tree estimate has no curvature bias here; the voxel estimate
// fits a plane per cell. For target_neighbours k in {8, ..., 128}: bias = mean estimate / truth
// - 1, rms = the per-point relative error (Poisson noise ~ 1/sqrt(k) plus the method's own),
// and the wall time with 1 and 2 threads, median of CANDI_BENCH_RUNS runs (default 3). "voxel,
// r given" passes the automatic radius in, so no kd-tree is built (the automatic radius needs
// one). Set CANDI_BENCH_POINTS to change the size.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/rng.h"
#include "sampling/density.h"

namespace {

using namespace candi;

constexpr double kPi = 3.14159265358979323846;
constexpr double kSphereRadius = 5.0;

size_t EnvCount(const char* name, size_t fallback) {
  const char* env = std::getenv(name);
  return env ? std::strtoull(env, nullptr, 10) : fallback;
}

PointCloud Sphere(size_t n) {
  PointCloud cloud;
  cloud.Resize(n);
  Rng rng(1);
  for (size_t i = 0; i < n; ++i) {
    Eigen::Vector3d d(rng.Normal(), rng.Normal(), rng.Normal());
    cloud.positions[i] = d.normalized() * kSphereRadius;
  }
  return cloud;
}

struct Timing {
  double ms = 0;
  sampling::DensityResult result;
};

Timing Run(const sampling::DensityOptions& options, const PointCloud& cloud, size_t runs) {
  std::vector<double> ms;
  Timing t;
  for (size_t k = 0; k < runs; ++k) {
    const auto start = std::chrono::steady_clock::now();
    t.result = sampling::EstimateSurfaceDensity(options, cloud);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                     .count());
  }
  std::sort(ms.begin(), ms.end());
  t.ms = ms[ms.size() / 2];
  return t;
}

void PrintRow(const char* label, int k, const sampling::DensityResult& r, double truth, double ms1,
              double ms2) {
  double sum = 0, sq = 0;
  for (double d : r.density) {
    sum += d / truth - 1;
    sq += (d / truth - 1) * (d / truth - 1);
  }
  const double n = static_cast<double>(r.density.size());
  std::printf("%-16s %5d %10.4f %+9.2f %8.2f %10.0f %10.0f\n", label, k, r.radius, 100 * sum / n,
              100 * std::sqrt(sq / n), ms1, ms2);
}

}  // namespace

int main() {
  const size_t n = EnvCount("CANDI_BENCH_POINTS", 1000000);
  const size_t runs = std::max<size_t>(1, EnvCount("CANDI_BENCH_RUNS", 3));
  const PointCloud cloud = Sphere(n);
  const double truth = static_cast<double>(n) / (4 * kPi * kSphereRadius * kSphereRadius);
  std::printf(
      "density: %zu points on a sphere of radius %.1f m, true density %.1f points/m^2, "
      "median of %zu runs\n\n",
      n, kSphereRadius, truth, runs);
  std::printf("%-16s %5s %10s %9s %8s %10s %10s\n", "method", "k", "radius m", "bias %", "rms %",
              "ms 1 thr", "ms 2 thr");
  for (sampling::DensityMethod method : {sampling::DensityMethod::kKdTree, sampling::DensityMethod::kVoxel}) {
    for (int k : {8, 16, 32, 64, 128}) {
      sampling::DensityOptions o;
      o.method = method;
      o.target_neighbours = k;
      o.threads = 1;
      const Timing one = Run(o, cloud, runs);
      o.threads = 2;
      const Timing two = Run(o, cloud, runs);
      PrintRow(sampling::DensityMethodName(method).c_str(), k, one.result, truth, one.ms, two.ms);
      if (method != sampling::DensityMethod::kVoxel) continue;
      o.radius = one.result.radius;
      o.threads = 1;
      const Timing given_one = Run(o, cloud, runs);
      o.threads = 2;
      const Timing given_two = Run(o, cloud, runs);
      PrintRow("voxel, r given", k, given_one.result, truth, given_one.ms, given_two.ms);
    }
  }
  return 0;
}

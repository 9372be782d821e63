// candi bench foundation (and bench/foundation_bench): accuracy vs time of the quality knobs, and the paper-scale run.
//
// 1. A hemisphere of radius 50 m drawn as 20001 exact vertices is resampled with N samples per
//    side and swept with M steps per half-turn; the surface error is the largest and the RMS
//    distance of the triangle centroids from the sphere (the analytic shape), and the time is the
//    profile (Hermite) + grid (sweep) + OpenMesh mesh build. Meshes over 4 M vertices are timed
//    without the OpenMesh build (marked "grid only").
// 2. The bundled example (examples/borobudur/foundation.dxf, four layers) at the defaults
//    (N = 1000, M = 90) with 4.47 M points in all, as in the paper's Table 1: wall time per stage
//    (DXF import, meshes, sampling; then writing the merged binary PLY with colours and layer
//    field, as `candi foundation` does, to a temporary file), on 1 and 2 threads without the CGAL
//    checks and on 2 threads with them. Median of CANDI_BENCH_RUNS runs (default 3).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "io/layer_clouds.h"
#include "mesh/foundation.h"
#include "sampling/layer_colours.h"
#include "sampling/surface_sampling.h"

namespace candi::bench {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadius = 50.0;

double Ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since)
      .count();
}

size_t EnvCount(const char* name, size_t fallback) {
  const char* env = std::getenv(name);
  return env ? std::strtoull(env, nullptr, 10) : fallback;
}

Polyline2 Hemisphere() {
  Polyline2 line;
  for (int k = 0; k <= 20000; ++k) {
    const double a = kPi * (1 - k / 20000.0);
    line.points.emplace_back(kRadius * std::cos(a), kRadius * std::sin(a));
  }
  return line;
}

// Max and RMS distance from the sphere of the centroids of the grid's triangles (the triangles
// BuildSurfaceMesh makes).
std::pair<double, double> SphereError(const mesh::SurfaceGrid& g) {
  double worst = 0, sum = 0;
  size_t count = 0;
  auto add = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
    const double d = ((a + b + c) / 3 + g.frame.origin).norm() - kRadius;
    worst = std::max(worst, std::abs(d));
    sum += d * d;
    ++count;
  };
  for (int i = 0; i + 1 < g.rings; ++i) {
    for (int j = 0; j < g.columns; ++j) {
      const int next = (j + 1) % g.columns;
      if (!(i == 0 && g.apex_top)) add(g.At(i, j), g.At(i, next), g.At(i + 1, j));
      add(g.At(i + 1, j), g.At(i, next), g.At(i + 1, next));
    }
  }
  return {worst, std::sqrt(sum / static_cast<double>(count))};
}

void AccuracyTable() {
  std::printf("hemisphere R = %.0f m: surface error (triangle centroids) and time\n", kRadius);
  std::printf("%6s %5s %11s %12s %12s %10s %10s %10s\n", "N", "M", "vertices", "max err m",
              "rms err m", "profile ms", "grid ms", "mesh ms");
  const Polyline2 line = Hemisphere();
  for (int n : {10, 100, 1000, 10000}) {
    for (int m : {8, 32, 128, 512}) {
      mesh::ProfileOptions po;
      po.samples_per_side = n;
      mesh::RevolveOptions ro;
      ro.angular_steps = m;
      ro.mode = mesh::RevolveMode::kSweep;
      auto t = std::chrono::steady_clock::now();
      const mesh::Profile profile = mesh::BuildProfile(po, line, {"hemisphere", "-"});
      const double profile_ms = Ms(t);
      t = std::chrono::steady_clock::now();
      const mesh::SurfaceGrid grid = mesh::RevolveProfile(ro, profile);
      const double grid_ms = Ms(t);
      const size_t vertices = static_cast<size_t>(n) * 2 * m;
      std::string mesh_ms = "grid only";
      if (vertices <= 4000000) {
        t = std::chrono::steady_clock::now();
        const TriMesh mesh = mesh::BuildSurfaceMesh({}, grid);
        char buf[32];
        std::snprintf(buf, sizeof(buf), "%.1f", Ms(t));
        mesh_ms = buf;
      }
      const auto [worst, rms] = SphereError(grid);
      std::printf("%6d %5d %11zu %12.3e %12.3e %10.1f %10.1f %10s\n", n, m, vertices, worst, rms,
                  profile_ms, grid_ms, mesh_ms.c_str());
    }
  }
}

struct Stages {
  double import_ms = 0, mesh_ms = 0, sample_ms = 0, write_ms = 0;
  size_t points = 0;
  double Total() const { return import_ms + mesh_ms + sample_ms; }
};

Stages PaperScale(const std::string& path, bool check, int threads, const std::string& output) {
  mesh::FoundationOptions o;
  o.check = check;
  Stages s;
  auto t = std::chrono::steady_clock::now();
  const mesh::DxfDrawing drawing = mesh::ReadDxf(o.dxf, path);
  s.import_ms = Ms(t);
  t = std::chrono::steady_clock::now();
  const std::vector<std::string> names = drawing.LayerNames();
  const std::vector<mesh::LayerSurface> layers = mesh::BuildLayerSurfaces(o, drawing, names, threads);
  std::vector<double> areas;
  for (const mesh::LayerSurface& layer : layers) areas.push_back(sampling::MeshArea(layer.mesh));  // as the CLI
  s.mesh_ms = Ms(t);
  t = std::chrono::steady_clock::now();
  const std::vector<uint64_t> counts = sampling::SplitCount(4470000, areas);
  std::vector<PointCloud> clouds;
  for (size_t k = 0; k < layers.size(); ++k) {
    sampling::SurfaceSampleOptions so;
    so.count = counts[k];
    so.threads = threads;
    so.colour = sampling::DefaultLayerColour(layers[k].layer, k).rgb;
    so.layer = static_cast<int>(k);
    clouds.push_back(sampling::SampleSurface(so, layers[k].mesh));
    s.points += clouds.back().size();
  }
  s.sample_ms = Ms(t);
  t = std::chrono::steady_clock::now();
  io::WriteLayerClouds(output, clouds, names);
  s.write_ms = Ms(t);
  return s;
}

void PaperScaleTable(size_t runs) {
  // From the repository root, else from the source tree this program was built from.
  std::string path = "examples/borobudur/foundation.dxf";
  if (!std::ifstream(path)) path = std::string(CANDI_SOURCE_DIR) + "/" + path;
  std::printf("\npaper scale: %s, 4 layers, N = 1000, M = 90, 4.47 M points, median of %zu\n",
              path.c_str(), runs);
  std::printf("%-28s %10s %10s %10s %10s %10s %10s\n", "", "import ms", "meshes ms", "sample ms",
              "total ms", "write ms", "points");
  const std::string output =
      (std::filesystem::temp_directory_path() / "candi_foundation_bench.ply").string();
  const struct {
    bool check;
    int threads;
    const char* name;
  } rows[] = {{false, 1, "without checks, 1 thread"},
              {false, 2, "without checks, 2 threads"},
              {true, 2, "with CGAL checks, 2 threads"}};
  for (const auto& row : rows) {
    std::vector<Stages> all;
    for (size_t r = 0; r < runs; ++r) all.push_back(PaperScale(path, row.check, row.threads, output));
    std::sort(all.begin(), all.end(),
              [](const Stages& a, const Stages& b) { return a.Total() < b.Total(); });
    const Stages& s = all[all.size() / 2];
    std::printf("%-28s %10.1f %10.1f %10.1f %10.1f %10.1f %10zu\n", row.name, s.import_ms,
                s.mesh_ms, s.sample_ms, s.Total(), s.write_ms, s.points);
  }
  std::filesystem::remove(output);
}

}  // namespace

int RunFoundationAccuracy() {
  AccuracyTable();
  PaperScaleTable(std::max<size_t>(1, EnvCount("CANDI_BENCH_RUNS", 3)));
  return 0;
}

}  // namespace candi::bench

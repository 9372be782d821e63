// candi bench section: what a section costs and how close it comes.
// 1. Accuracy vs time on the bundled foundation (its points from the drawing, at the default
//    density): the section at the drawing's plane, read back from its DXF with candi's own reader,
//    against the profiles the layers were built from, for several slab thicknesses.
// 2. Scale: generated archives (bench view's terraced solid) of 1e7, 1e8 (1e9) points, a vertical
//    section through the middle: chunks read of all, points read, seconds, peak memory.
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "bench/archives.h"
#include "bench/bench.h"
#include "core/atomic_file.h"
#include "core/check.h"
#include "core/log.h"
#include "core/polyline.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "core/timer.h"
#include "io/layer_clouds.h"
#include "mesh/dxf_import.h"
#include "mesh/foundation.h"
#include "pipeline/foundation.h"
#include "pipeline/section.h"
#include "render/archive.h"
#include "render/archive_pack.h"
#include "render/synthetic_scene.h"

namespace candi::bench {

namespace {

namespace fs = std::filesystem;

double PeakMb() {
  struct rusage u {};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;
}

void FoundationTable(const SectionBenchOptions& a, const std::string& dir) {
  const std::string drawing_path = a.drawing;
  const std::string ply = dir + "/foundation.ply";
  pipeline::FoundationPointsOptions f;
  f.surface.check_options.self_intersections = false;
  f.sample.density = pipeline::kDefaultFoundationDensity;
  f.sample.threads = a.threads;
  const pipeline::FoundationPoints points = pipeline::DigitizeFoundation(f, drawing_path);
  io::WriteLayerClouds(ply, points.clouds, points.Names());
  const mesh::FoundationOptions o;
  const mesh::DxfDrawing drawing = mesh::ReadDxf(o.dxf, drawing_path);
  std::map<std::string, std::vector<Eigen::Vector2d>> profiles;
  for (const std::string& layer : drawing.LayerNames()) {
    const mesh::Profile p = mesh::BuildProfile(o.profile, mesh::LayerSection(o, drawing, layer), {drawing_path, layer});
    std::vector<Eigen::Vector2d>& line = profiles[layer];
    for (auto it = p.left.rbegin(); it != p.left.rend(); ++it) line.push_back(*it + p.origin);
    for (size_t i = 1; i < p.right.size(); ++i) line.push_back(p.right[i] + p.origin);
  }
  std::printf("\nfoundation (%s, default density): the section at the drawing's plane against the drawing's "
              "profiles, per thickness (all layers)\n", drawing_path.c_str());
  std::printf("%12s %12s %10s %12s %12s %10s\n", "thickness m", "slab points", "vertices", "mean mm", "max mm", "s");
  for (double t : {0.02, 0.05, 0.1, 0.2, 0.5}) {
    pipeline::SectionOptions s;
    s.threads = a.threads;
    const std::string output = dir + "/foundation-section";
    const Stopwatch watch;
    const section::SectionPath path = section::SectionPath::Plane({0, 0, 0}, {0, 1, 0}, t);
    pipeline::WriteSection(pipeline::CutSection(s, {ply}, path, ClipRegion{}), path, output);
    const double seconds = watch.Seconds();
    const nlohmann::json j = nlohmann::json::parse(ReadFileToString(output + "/section.json"));
    const mesh::DxfDrawing section = mesh::ReadDxf(mesh::DxfReadOptions{}, output + "/section.dxf");
    double sum = 0, worst = 0;
    size_t n = 0;
    for (const auto& [layer, lines] : section.layers) {
      const auto ref = profiles.find(layer);
      if (ref == profiles.end()) continue;
      for (const Polyline2& line : lines) {
        for (const Eigen::Vector2d& v : line.points) {
          const double e = DistanceToPolyline(v, ref->second);
          sum += e, worst = std::max(worst, e), ++n;
        }
      }
    }
    std::printf("%12.2f %12llu %10zu %12.2f %12.2f %10.2f\n", t,
                static_cast<unsigned long long>(j.at("points").get<uint64_t>()), n, n ? 1e3 * sum / n : 0.0,
                1e3 * worst, seconds);
    std::fflush(stdout);
  }
}

}  // namespace

void SectionBenchOptions::Check() const {
  CANDI_CHECK_OPTION(thickness > 0 && std::isfinite(thickness), thickness, "> 0 m");
  CANDI_CHECK_OPTION_IN(threads, 0, 256);
}

int RunSectionBench(const SectionBenchOptions& a) {
  a.Check();
  const std::vector<uint64_t> sizes = ParseBenchSizes(a.sizes, a.billion);
  const std::string dir = fs::absolute(a.work_dir).string();
  fs::create_directories(dir);
  std::printf("candi bench section: %d thread(s) (0: all)\n", a.threads);
  if (!a.drawing.empty()) FoundationTable(a, dir);
  std::printf("\nscale: a vertical section %.2f m thick through the middle of the terraced solid (archive on disk)\n",
              a.thickness);
  std::printf("%12s %8s %14s %14s %12s %8s %8s %8s %8s %9s\n", "points", "pack s", "chunks read", "points read",
              "slab points", "read s", "lines s", "image s", "total s", "peak MB");
  for (uint64_t n : sizes) {
    double pack_s = 0;
    const std::string archive_dir = BenchArchive(dir, n, a.keep, "bench section", &pack_s);
    Eigen::Vector3d centre;
    {
      const render::Archive archive(archive_dir);
      centre = archive.manifest().bounds.Translated(archive.manifest().frame.origin).Center();
    }
    pipeline::SectionOptions s;
    s.threads = a.threads;
    const Stopwatch watch;
    const section::SectionPath path = section::SectionPath::Plane(centre, {1, 0.3, 0}, a.thickness);
    const pipeline::SectionCut cut = pipeline::CutSection(s, {archive_dir}, path, ClipRegion{});
    pipeline::WriteSection(cut, path, dir + "/scene-section");
    const double seconds = watch.Seconds();
    const nlohmann::json j = nlohmann::json::parse(cut.summary);
    char chunks[64];
    std::snprintf(chunks, sizeof(chunks), "%llu/%llu", static_cast<unsigned long long>(j.at("chunks_read").get<uint64_t>()),
                  static_cast<unsigned long long>(j.at("chunks").get<uint64_t>()));
    const nlohmann::json& t = j.at("seconds");
    std::printf("%12llu %8.1f %14s %14llu %12llu %8.2f %8.2f %8.2f %8.2f %9.0f\n", static_cast<unsigned long long>(n),
                pack_s, chunks, static_cast<unsigned long long>(j.at("points_read").get<uint64_t>()),
                static_cast<unsigned long long>(j.at("points").get<uint64_t>()), t.at("read").get<double>(),
                t.at("lines").get<double>(), t.at("image").get<double>(), seconds, PeakMb());
    std::fflush(stdout);
    if (!a.keep) fs::remove_all(archive_dir);
  }
  return 0;
}

}  // namespace candi::bench

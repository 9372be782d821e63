// Raw point files to a first image: what `candi render FILE` (and `candi pack FILE`) cost on a
// user's own binary PLY (double x, y, z and colour) and LAS (format 2), against what the page
// cache allows. For each file and thread count, the median of --runs runs of:
//   page cache  reading the file's bytes with no parsing (the limit of any reader);
//   read        io::ReadPointCloud (the points in memory, doubles);
//   prepare     render::BuildSplatCloud (render frame, Morton order, ensembles, quantization);
//   draw        render::RenderSpbr at L = 100, 1024 x 768;
//   memory      pipeline::RenderPointFiles in memory mode and the PNG written (read + prepare +
//               draw + bounds, brightness and PNG: `candi render --mode memory FILE`);
//   bounds      io::RecordBounds, the bounds of the file's records read in place (the stream
//               render's first pass over the file; nothing for XYZ, whose points are not records);
//   end to end  pipeline::RenderPointFiles in auto mode and the PNG written (what `candi render
//               FILE` does: from 10^6 points of records, streamed in place: bounds, then the
//               records staged and drawn);
//   pack        render::PackFiles (what `candi pack FILE` does).
// The files are generated once (a seeded terrain) in --dir and kept for later runs; a text XYZ
// file of --xyz-points (default a tenth of --points) is read too. --read-only times the page cache
// and the read alone; --no-memory skips read, prepare, draw and memory (minutes at 10^8).
//
//   first_image_bench [--points 2e7] [--xyz-points 2e6] [--runs 3] [--threads 1,2] [--read-only]
//                     [--no-memory] [--dir candi-bench-first-image]
#include <fcntl.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/mapped_file.h"
#include "core/rng.h"
#include "io/point_io.h"
#include "io/point_records.h"
#include "pipeline/render.h"
#include "render/archive_pack.h"
#include "render/first_view.h"
#include "render/spbr.h"
#include "render/splat_cloud.h"

namespace {

using namespace candi;
namespace fs = std::filesystem;

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double Timed(int runs, const std::function<void()>& f) {
  std::vector<double> s;
  for (int r = 0; r < runs; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    s.push_back(Seconds(t0));
  }
  return Median(s);
}

// A terrain of `n` points at survey coordinates (E 416000, N 9168000), coloured by height.
PointCloud Terrain(uint64_t n, uint64_t seed) {
  PointCloud c;
  c.schema.colors = true;
  c.schema.position_type = ScalarType::kFloat64;
  c.SetSchema(c.schema);
  c.frame.origin = Eigen::Vector3d(416000, 9168000, 200);
  c.Resize(n);
  Rng rng(seed);
  for (uint64_t i = 0; i < n; ++i) {
    const double x = rng.Uniform(0, 300), y = rng.Uniform(0, 300);
    const double z = 8 * std::sin(x / 40) * std::cos(y / 55) + 0.02 * rng.Normal();
    c.positions[i] = Eigen::Vector3d(x, y, z);
    const uint8_t g = static_cast<uint8_t>(std::clamp(128 + 14 * z, 0.0, 255.0));
    c.colors[i] = {g, static_cast<uint8_t>(255 - g), 96};
  }
  return c;
}

// Reads the whole file in 64 MiB blocks, no parsing.
void ReadBytes(const std::string& path) {
  const int fd = open(path.c_str(), O_RDONLY);
  if (fd < 0) throw std::runtime_error("cannot open " + path);
  std::vector<char> buffer(size_t{64} << 20);
  uint64_t sum = 0;
  ssize_t got;
  while ((got = read(fd, buffer.data(), buffer.size())) > 0) sum += static_cast<uint8_t>(buffer[got - 1]);
  close(fd);
  if (sum == 0xFFFFFFFFFFFFFFFFull) std::puts("");  // (keeps the reads)
}

std::vector<int> ParseThreads(const std::string& text) {
  std::vector<int> out;
  size_t at = 0;
  while (at <= text.size()) {
    const size_t comma = std::min(text.find(',', at), text.size());
    out.push_back(std::stoi(text.substr(at, comma - at)));
    at = comma + 1;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  uint64_t points = 20000000, xyz_points = 0;
  bool read_only = false, memory = true;
  int runs = 3;
  std::string threads_text = "1,2", dir = "candi-bench-first-image";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--points" && has_value) points = static_cast<uint64_t>(std::stod(argv[++i]));
    else if (a == "--xyz-points" && has_value) xyz_points = static_cast<uint64_t>(std::stod(argv[++i]));
    else if (a == "--read-only") read_only = true;
    else if (a == "--no-memory") memory = false;
    else if (a == "--runs" && has_value) runs = std::max(1, std::atoi(argv[++i]));
    else if (a == "--threads" && has_value) threads_text = argv[++i];
    else if (a == "--dir" && has_value) dir = argv[++i];
    else {
      std::fprintf(stderr, "usage: first_image_bench [--points 2e7] [--xyz-points 2e6] [--runs 3] [--threads 1,2] "
                           "[--read-only] [--no-memory] [--dir DIR]\n");
      return 2;
    }
  }
  fs::create_directories(dir);
  const std::string tag = std::to_string(points);
  if (xyz_points == 0) xyz_points = points / 10;
  const std::vector<std::string> files = {dir + "/terrain-" + tag + ".ply", dir + "/terrain-" + tag + ".las",
                                          dir + "/terrain-" + std::to_string(xyz_points) + ".xyz"};
  for (const std::string& f : files) {
    if (fs::exists(f)) continue;
    std::fprintf(stderr, "writing %s\n", f.c_str());
    io::WritePointCloud(f, Terrain(fs::path(f).extension() == ".xyz" ? xyz_points : points, 1));
  }

  std::printf("first_image_bench: %llu points a file, median of %d run(s); M points/s in brackets\n\n",
              static_cast<unsigned long long>(points), runs);
  std::printf("%-28s %4s %17s %15s %15s %15s %15s %15s %17s %15s\n", "file", "thr", "page cache s", "read s",
              "prepare s", "draw s", "memory s", "bounds s", "end to end s", "pack s");
  double m = 0;
  auto cell = [&m](double s) {
    char text[32];
    if (s < 0) return std::string("-");
    std::snprintf(text, sizeof(text), "%.2f (%.1f)", s, m / s);
    return std::string(text);
  };
  for (const std::string& file : files) {
    m = static_cast<double>(fs::path(file).extension() == ".xyz" ? xyz_points : points) * 1e-6;
    ReadBytes(file);  // into the page cache
    for (int t : ParseThreads(threads_text)) {
      tbb::global_control limit(tbb::global_control::max_allowed_parallelism, static_cast<size_t>(t));
      const double bytes_s = Timed(runs, [&] { ReadBytes(file); });
      const double gb = static_cast<double>(fs::file_size(file)) * 1e-9;
      char page[32];
      std::snprintf(page, sizeof(page), "%.2f (%.1f GB/s)", bytes_s, gb / bytes_s);
      PointCloud cloud;
      double read_s = -1, prepare_s = -1, draw_s = -1, memory_s = -1, bounds_s = -1;
      if (memory || read_only) read_s = Timed(runs, [&] { cloud = io::ReadPointCloud(file); });
      if (read_only) {
        std::printf("%-28s %4d %17s %15s\n", fs::path(file).filename().c_str(), t, page, cell(read_s).c_str());
        std::fflush(stdout);
        continue;
      }
      const std::string png = dir + "/first.png";
      auto render_file = [&](pipeline::RenderMode mode) {
        pipeline::RenderOptions o;
        o.mode = mode;
        pipeline::RenderOutputs out;
        out.png = png;
        pipeline::WriteRender(o, pipeline::RenderPointFiles(o, {file}), out);
      };
      if (memory) {
        render::SplatCloudOptions so;
        so.spbr.repeat_level = 100;
        render::SplatCloud splats;
        prepare_s = Timed(runs, [&] { splats = render::BuildSplatCloud(so, {&cloud}); });
        render::Camera camera = render::FirstView(cloud.WorldBounds(), 1024, 768, render::Orientation());
        camera.eye -= splats.frame.origin;
        camera.target -= splats.frame.origin;
        render::SpbrOptions spbr;
        draw_s = Timed(runs, [&] { render::RenderSpbr(spbr, camera, splats); });
        splats = render::SplatCloud();
        cloud = PointCloud();
        memory_s = Timed(runs, [&] { render_file(pipeline::RenderMode::kMemory); });
      }
      if (const auto layout = io::OpenPointReader(file)->record_layout()) {
        bounds_s = Timed(runs, [&] {
          const MappedFile map(file);
          if (!io::RecordBounds(map, *layout)) throw std::runtime_error(file + ": records not read");
        });
      }
      const double end_s = Timed(runs, [&] { render_file(pipeline::RenderMode::kAuto); });
      const double pack_s = Timed(runs, [&] { render::PackFiles(render::PackOptions(), {file}, "", dir + "/packed"); });
      std::printf("%-28s %4d %17s %15s %15s %15s %15s %15s %17s %15s\n", fs::path(file).filename().c_str(), t, page,
                  cell(read_s).c_str(), cell(prepare_s).c_str(), cell(draw_s).c_str(), cell(memory_s).c_str(),
                  cell(bounds_s).c_str(), cell(end_s).c_str(), cell(pack_s).c_str());
      std::fflush(stdout);
    }
  }
  std::printf("\nmemory: read + prepare + draw, the bounds, the brightness and the PNG. end to end: what candi render "
              "FILE does (from 10^6 points of records: streamed in place, bounds first).\n");
  return 0;
}

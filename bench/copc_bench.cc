// Writing COPC (a .copc.laz name) against LAS and LAZ: seconds, M points/s, peak RSS and bytes a
// point for a generated airborne scan (seeded: flight strips of zigzag scan lines over a wavy
// terrain, 5.5 points/m^2, with colour, intensity and GPS time; LAS 1.2 format 3, COPC 1.4
// format 7), streamed to the writer in chunks of 2^20 points as a conversion streams them.
// Each case runs in a child process of its own, so its peak RSS (getrusage) is its own; the
// seconds are those of the writer's Write and Close calls (the generation is not counted), and
// split: "in" the Write calls, then Close: for COPC its "octree" (until the writer reports its
// chunks stage) and "chunks" (the rest), for LAS and LAZ all "chunks". "user" and "sys" are the
// CPU seconds of the process's threads in those calls (getrusage): sys is mostly the kernel's
// first touch of fresh memory and page cache, which on a VM varies several-fold from run to run.
//
// --copc-memory MB: the memory a COPC file's records may take before they are spilled beside it
// (io::CopcWriteOptions::memory_bytes; default: half the machine's).
//
//   copc_bench [--points 1e6,1e7] [--threads 1,2] [--formats las,laz,copc.laz] [--dir DIR]
//              [--copc-memory MB] [--keep]
#include <sys/resource.h>
#include <sys/wait.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "core/rng.h"
#include "io/las/las_io.h"
#include "io/point_io.h"

namespace {

using namespace candi;
namespace fs = std::filesystem;

constexpr size_t kChunkPoints = size_t{1} << 20;
constexpr int kScanLinePoints = 500;      // across a 300 m swath
constexpr double kSwath = 300.0;          // m
constexpr double kLineStep = 0.3;         // m between scan lines
constexpr double kStripLength = 2000.0;   // m, then the next strip 250 m aside
constexpr double kStripStep = 250.0;

PointSchema ScanSchema() {
  PointSchema s;
  s.colors = true;
  s.scalars = {{io::las_field::kIntensity, ScalarType::kFloat32},
               {io::las_field::kGpsTime, ScalarType::kFloat64}};
  return s;
}

// Points [first, first + n) of the scan: the i-th point's place depends on i alone, its noise on
// the generator, which runs through the points in order.
void ScanChunk(uint64_t first, size_t n, Rng* rng, PointCloud* c) {
  c->Resize(n);
  const uint64_t lines_per_strip = static_cast<uint64_t>(kStripLength / kLineStep);
  for (size_t j = 0; j < n; ++j) {
    const uint64_t i = first + j;
    const uint64_t line = i / kScanLinePoints, strip = line / lines_per_strip;
    const uint64_t in_line = i % kScanLinePoints;
    const double across = (line % 2 ? kScanLinePoints - 1 - in_line : in_line) *
                          (kSwath / kScanLinePoints);
    const double along = static_cast<double>(line % lines_per_strip) * kLineStep;
    const double x = strip * kStripStep + across + 0.05 * rng->Uniform(),
                 y = (strip % 2 ? kStripLength - along : along) + 0.05 * rng->Uniform();
    const double z = 12 * std::sin(x / 130) * std::cos(y / 170) + 3 * std::sin(x / 17 + y / 23) +
                     0.03 * rng->Uniform();
    c->positions[j] = Eigen::Vector3d(x, y, z);
    const uint8_t g = static_cast<uint8_t>(std::clamp(128 + 8 * z, 0.0, 255.0));
    c->colors[j] = {g, static_cast<uint8_t>(255 - g), static_cast<uint8_t>(rng->Uniform(60, 90))};
    c->scalars[0].f32[j] = static_cast<float>(std::floor(rng->Uniform(200, 1200)));
    c->scalars[1].f64[j] = 3.0e5 + 1e-5 * static_cast<double>(i);
  }
}

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Split {
  double in = 0.0, octree = 0.0, chunks = 0.0;
  double user = 0.0, sys = 0.0;  // CPU seconds in the writer's calls, all threads
  double Total() const { return in + octree + chunks; }
};

// The process's user and system CPU seconds so far.
std::pair<double, double> CpuSeconds() {
  struct rusage u;
  getrusage(RUSAGE_SELF, &u);
  auto s = [](const timeval& t) { return static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_usec); };
  return {s(u.ru_utime), s(u.ru_stime)};
}

// Adds the CPU seconds since `from` to split's.
void AddCpu(const std::pair<double, double>& from, Split* split) {
  const std::pair<double, double> now = CpuSeconds();
  split->user += now.first - from.first;
  split->sys += now.second - from.second;
}

// Writes `points` points of the scan to `path` on `threads` threads; the writer's seconds.
Split WriteScan(const std::string& path, uint64_t points, int threads, uint64_t copc_memory) {
  tbb::global_control limit(tbb::global_control::max_allowed_parallelism,
                            static_cast<size_t>(threads));
  PointCloud chunk;
  chunk.SetSchema(ScanSchema());
  chunk.frame.origin = Eigen::Vector3d(416000, 9168000, 200);
  io::PointWriteSpec spec;
  spec.schema = chunk.schema;
  spec.frame = chunk.frame;
  spec.count = points;
  io::PointWriteOptions options;
  options.las_scale = Eigen::Vector3d::Constant(0.001);
  options.copc.memory_bytes = copc_memory;
  bool chunks_started = false;
  std::chrono::steady_clock::time_point chunks_t0;
  options.close_progress = [&](const std::string& stage, uint64_t, uint64_t) {
    if (stage != "chunks" || chunks_started) return;
    chunks_started = true;
    chunks_t0 = std::chrono::steady_clock::now();
  };
  Rng rng(1);
  Split split;
  auto cpu0 = CpuSeconds();
  auto t0 = std::chrono::steady_clock::now();
  const std::unique_ptr<io::PointWriter> writer = io::OpenPointWriter(path, spec, options);
  split.in += Seconds(t0);
  AddCpu(cpu0, &split);
  for (uint64_t first = 0; first < points; first += kChunkPoints) {
    ScanChunk(first, static_cast<size_t>(std::min<uint64_t>(kChunkPoints, points - first)), &rng,
              &chunk);
    cpu0 = CpuSeconds();
    t0 = std::chrono::steady_clock::now();
    writer->Write(chunk);
    split.in += Seconds(t0);
    AddCpu(cpu0, &split);
  }
  cpu0 = CpuSeconds();
  t0 = std::chrono::steady_clock::now();
  writer->Close();
  const double close = Seconds(t0);
  AddCpu(cpu0, &split);
  split.chunks = chunks_started ? Seconds(chunks_t0) : close;
  split.octree = close - split.chunks;
  return split;
}

// One case in a child process: prints its row.
void RunCase(const std::string& path, uint64_t points, int threads, uint64_t copc_memory,
             bool keep) {
  std::fflush(stdout);
  const pid_t pid = fork();
  if (pid == 0) {
    const Split split = WriteScan(path, points, threads, copc_memory);
    const double s = split.Total();
    struct rusage usage;
    getrusage(RUSAGE_SELF, &usage);
    const double bytes = static_cast<double>(fs::file_size(path));
    const double n = static_cast<double>(points);
    const std::string name = fs::path(path).filename().string();
    std::printf("%-14s %12llu %4d %10.2f %10.2f %12.2f %12.2f %7.2f %7.2f %7.2f %7.2f %7.2f\n",
                name.substr(name.find('.') + 1).c_str(), static_cast<unsigned long long>(points),
                threads, s, n * 1e-6 / s, usage.ru_maxrss / 1048576.0, bytes / n, split.in,
                split.octree, split.chunks, split.user, split.sys);
    std::fflush(stdout);
    if (!keep) fs::remove(path);
    std::_Exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::printf("%s: the case failed (status %d)\n", path.c_str(), status);
  }
}

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> out;
  size_t at = 0;
  while (at <= text.size()) {
    const size_t comma = std::min(text.find(',', at), text.size());
    out.push_back(text.substr(at, comma - at));
    at = comma + 1;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::string points_text = "1e6,1e7", threads_text = "1,2", formats_text = "las,laz,copc.laz";
  std::string dir = "candi-bench-copc";
  bool keep = false;
  uint64_t copc_memory = 0;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--points" && has_value) points_text = argv[++i];
    else if (a == "--threads" && has_value) threads_text = argv[++i];
    else if (a == "--formats" && has_value) formats_text = argv[++i];
    else if (a == "--dir" && has_value) dir = argv[++i];
    else if (a == "--copc-memory" && has_value)
      copc_memory = static_cast<uint64_t>(std::stod(argv[++i]) * 1048576.0);
    else if (a == "--keep") keep = true;
    else {
      std::fprintf(stderr,
                   "usage: copc_bench [--points 1e6,1e7] [--threads 1,2] "
                   "[--formats las,laz,copc.laz] [--dir DIR] [--copc-memory MB] [--keep]\n");
      return 2;
    }
  }
  fs::create_directories(dir);
  std::printf("copc_bench: a generated airborne scan written through io::OpenPointWriter\n");
  std::printf("%-14s %12s %4s %10s %10s %12s %12s %7s %7s %7s %7s %7s\n", "format", "points", "thr",
              "seconds", "M pts/s", "peak RSS GiB", "bytes/point", "in s", "octree", "chunks",
              "user s", "sys s");
  for (const std::string& p : SplitList(points_text)) {
    const uint64_t points = static_cast<uint64_t>(std::stod(p));
    for (const std::string& format : SplitList(formats_text)) {
      for (const std::string& t : SplitList(threads_text)) {
        RunCase(dir + "/scan." + format, points, std::stoi(t), copc_memory, keep);
      }
    }
  }
  std::error_code ignored;
  fs::remove(dir, ignored);  // when empty
  return 0;
}

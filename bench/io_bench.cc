// Point-file throughput: binary PLY (float and double positions), LAS (point format 3) and E57
// (float and double Cartesian fields), read and write, 10^7 points with colour, from and to the
// page cache; and LAZ decoding of files other tools wrote (../shared/data/las/autzen_trim.laz,
// pointwise v2, format 3; tests/data/laz/append-bug.laz, layered v3, format 8), each read
// repeatedly, on 1 and 2 threads. Prints Google Benchmark's table with points/s; medians of 5
// repetitions. Targets: read >= 50 M points/s, write >= 30 M points/s (issue 2); E57 float read
// >= 20 M points/s, LAZ >= 10 M points/s on one core (issue 25). LAZ writing (issue 38, target
// >= 3 M points/s a core): the Autzen points (real lidar, format 3) written 10 times and the
// synthetic cloud once, as .laz on 1 and 2 threads; the label gives the bytes a point against
// LAS, and the encoder alone compresses LAS records into chunks. Set CANDI_BENCH_POINTS to change
// the size. COPC writing (issue 38): the same clouds as .copc.laz, with the octree's size.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <tbb/global_control.h>

#include "core/binary_file.h"
#include "core/rng.h"
#include "io/copc/copc_write.h"
#include "io/las/las_header.h"
#include "io/laz/laz_chunks.h"
#include "io/laz/laz_format.h"
#include "io/point_io.h"

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
                       {"fmt3.las", ScalarType::kFloat64},  {"float.e57", ScalarType::kFloat32},
                       {"double.e57", ScalarType::kFloat64}};

void BM_Write(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  const PointCloud& cloud = Cloud(c.type);
  for (auto _ : state) io::WritePointCloud(Dir() + "/" + c.file, cloud);
  state.SetItemsProcessed(state.iterations() * cloud.size());
  state.SetLabel(c.file);
}

// range(1) = 0: every field (lossless); 1: geometry and colour only (PointReadOptions::scalar_fields).
void BM_Read(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  const std::string path = Dir() + "/" + c.file;
  if (!std::filesystem::exists(path)) io::WritePointCloud(path, Cloud(c.type));
  io::PointReadOptions options;
  options.scalar_fields = state.range(1) == 0;
  size_t n = 0;
  for (auto _ : state) {
    auto reader = io::OpenPointReader(path, options);
    PointCloud chunk;
    n = 0;
    while (size_t got = reader->Read(1 << 16, &chunk)) n += got;
    benchmark::DoNotOptimize(chunk.positions.data());
  }
  state.SetItemsProcessed(state.iterations() * n);
  state.SetLabel(std::string(c.file) + (options.scalar_fields ? "" : " xyz+rgb only"));
}

// LAZ written by other tools, read `repeat` times; range(0): file, range(1): threads,
// range(2) = 0: every field, 1: geometry and colour only.
struct LazCase {
  const char* path;  // relative to the repository
  int repeat;
};
const LazCase kLazCases[] = {{"../shared/data/las/autzen_trim.laz", 30}, {"tests/data/laz/append-bug.laz", 80}};

void BM_ReadLaz(benchmark::State& state) {
  const LazCase& c = kLazCases[state.range(0)];
  const std::string path = std::string(CANDI_SOURCE_DIR) + "/" + c.path;
  if (!std::filesystem::exists(path)) {
    state.SkipWithError((path + " is absent").c_str());
    return;
  }
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(1));
  io::PointReadOptions options;
  options.scalar_fields = state.range(2) == 0;
  size_t n = 0;
  std::string description;
  for (auto _ : state) {
    n = 0;
    for (int r = 0; r < c.repeat; ++r) {
      auto reader = io::OpenPointReader(path, options);
      description = reader->info().description;
      PointCloud chunk;
      while (size_t got = reader->Read(1 << 16, &chunk)) n += got;
      benchmark::DoNotOptimize(chunk.positions.data());
    }
  }
  state.SetItemsProcessed(state.iterations() * n);
  state.SetLabel(std::filesystem::path(c.path).filename().string() + ", " + std::to_string(state.range(1)) +
                 " thread(s)" + (options.scalar_fields ? "" : ", xyz+rgb only") + " [" +
                 description.substr(0, description.find(',')) + "]");
}

// Writes the cloud of range(0) (0: ../shared/data/las/autzen_trim.las, 10 times; 1: the
// synthetic double cloud, once) to Dir()/write<ext> on range(1) threads; the label gives the
// bytes a point against LAS, and `tree` of the file when set.
void WriteBench(benchmark::State& state, const std::string& ext, const char* name,
                std::string (*tree)(const std::string&)) {
  PointCloud autzen;
  const bool real = state.range(0) == 0;
  if (real) {
    const std::string path = std::string(CANDI_SOURCE_DIR) + "/../shared/data/las/autzen_trim.las";
    if (!std::filesystem::exists(path)) {
      state.SkipWithError((path + " is absent").c_str());
      return;
    }
    autzen = io::ReadPointCloud(path);
  }
  const PointCloud& cloud = real ? autzen : Cloud(ScalarType::kFloat64);
  const int repeat = real ? 10 : 1;
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(1));
  const std::string out = Dir() + "/write" + ext, las = Dir() + "/write.las";
  for (auto _ : state) {
    for (int r = 0; r < repeat; ++r) io::WritePointCloud(out, cloud);
  }
  state.SetItemsProcessed(state.iterations() * repeat * cloud.size());
  io::WritePointCloud(las, cloud);
  const double n = static_cast<double>(cloud.size());
  char label[200];
  std::snprintf(label, sizeof label, "%s, %d thread(s): %s %.2f bytes/point, LAS %.2f%s%s",
                real ? "autzen_trim" : "synthetic", static_cast<int>(state.range(1)), name,
                std::filesystem::file_size(out) / n, std::filesystem::file_size(las) / n,
                tree ? "; " : "", tree ? tree(out).c_str() : "");
  state.SetLabel(label);
}

// range(0) = 0: ../shared/data/las/autzen_trim.las written 10 times; 1: the synthetic double
// cloud (LAS format 3 with colour) once. range(1): threads.
void BM_WriteLaz(benchmark::State& state) { WriteBench(state, ".laz", "LAZ", nullptr); }

// The encoder alone: LAS records (read from a LAS file's bytes) compressed into LAZ chunks, the
// chunks dropped. range(0) = 0: autzen_trim.las (format 3, pointwise v2) 10 times; 1: the
// synthetic cloud written as LAS 1.4 format 7 (layered v3). range(1): threads.
void BM_CompressLaz(benchmark::State& state) {
  const bool real = state.range(0) == 0;
  std::string path = std::string(CANDI_SOURCE_DIR) + "/../shared/data/las/autzen_trim.las";
  if (!real) {
    path = Dir() + "/fmt7.las";
    io::PointWriteOptions options;
    options.las_point_format = 7;
    options.las_version_minor = 4;
    if (!std::filesystem::exists(path)) io::WritePointCloud(path, Cloud(ScalarType::kFloat64), options);
  }
  if (!std::filesystem::exists(path)) {
    state.SkipWithError((path + " is absent").c_str());
    return;
  }
  BinaryFile file(path);
  io::LasHeader header = io::ReadLasHeader(&file);
  const uint64_t count = io::LasPointCount(header);
  std::vector<uint8_t> records(count * header.record_length);
  file.ReadAt(header.offset_to_point_data, records.data(), records.size());
  const int extra = header.record_length - io::LasLayoutOf(header.point_format).record_size;
  const io::laz::Vlr vlr = io::laz::WriterVlr(header.point_format, extra, 50000);
  const int repeat = real ? 10 : 1;
  tbb::global_control threads(tbb::global_control::max_allowed_parallelism, state.range(1));
  size_t bytes = 0;
  for (auto _ : state) {
    for (int r = 0; r < repeat; ++r) {
      bytes = 0;
      io::LazChunkWriter writer(vlr, header.record_length, [&](const uint8_t*, size_t n) { bytes += n; });
      writer.Add(records.data(), count);
      bytes += writer.Finish().size();
    }
  }
  state.SetItemsProcessed(state.iterations() * repeat * count);
  char label[160];
  std::snprintf(label, sizeof label, "%s, format %d, %d thread(s): %.2f bytes/point, LAS records %d",
                real ? "autzen_trim" : "synthetic", header.point_format, static_cast<int>(state.range(1)),
                static_cast<double>(bytes) / count, header.record_length);
  state.SetLabel(label);
}

// The nodes and depth of a COPC file's hierarchy (its root page holds every node).
std::string CopcTree(const std::string& path) {
  BinaryFile file(path);
  const io::LasHeader header = io::ReadLasHeader(&file);
  const io::CopcInfo info = io::ParseCopcInfo(io::ReadLasVlrs(&file, header).front().data);
  std::string page(info.root_hier_size, '\0');
  file.ReadAt(info.root_hier_offset, page.data(), page.size());
  int depth = 0;
  const std::vector<io::CopcEntry> entries = io::ParseCopcHierarchy(page);
  for (const io::CopcEntry& e : entries) depth = std::max(depth, e.key.level);
  return std::to_string(entries.size()) + " nodes, depth " + std::to_string(depth);
}

// COPC writing (issue 38, target >= 5 M points/s on 2 cores for 10^8 points): range(0) = 0: the
// Autzen points written 10 times; 1: the synthetic cloud (uniform in 100 x 100 x 30 m, format 7)
// once, as .copc.laz. range(1): threads. The label gives bytes a point against LAS, and the tree.
void BM_WriteCopc(benchmark::State& state) { WriteBench(state, ".copc.laz", "COPC", CopcTree); }

BENCHMARK(BM_Write)->DenseRange(0, 4)->Unit(benchmark::kMillisecond)->UseRealTime()
    ->Repetitions(5)->ReportAggregatesOnly(true)->Iterations(1);
BENCHMARK(BM_Read)->ArgsProduct({{0, 1, 2, 3, 4}, {0}})->Args({2, 1})->Unit(benchmark::kMillisecond)->UseRealTime()
    ->Repetitions(5)->ReportAggregatesOnly(true)->Iterations(1);
BENCHMARK(BM_ReadLaz)->ArgsProduct({{0, 1}, {1, 2}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime()
    ->Repetitions(5)->ReportAggregatesOnly(true)->Iterations(1);
BENCHMARK(BM_CompressLaz)->ArgsProduct({{0, 1}, {1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime()
    ->Repetitions(3)->ReportAggregatesOnly(true)->Iterations(1);
BENCHMARK(BM_WriteLaz)->ArgsProduct({{0, 1}, {1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime()
    ->Repetitions(3)->ReportAggregatesOnly(true)->Iterations(1);
BENCHMARK(BM_WriteCopc)->ArgsProduct({{0, 1}, {1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime()
    ->Repetitions(3)->ReportAggregatesOnly(true)->Iterations(1);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  std::filesystem::remove_all(Dir());
  return 0;
}

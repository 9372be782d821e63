// candi bench scale: pack and render generated scenes (the terraced solid of the example, same
// shape at every size) of 1e7, 1e8 (and 1e9) points. Packing and rendering run as child
// processes of this executable (`candi pack`, `candi render`, `mpirun -np K candi render`), so
// each one's wall time and peak resident memory (wait4) are its own. The MPI image is compared
// with the one-process image pixel for pixel.
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/archives.h"
#include "bench/child_run.h"
#include "bench/bench.h"
#include "core/check.h"
#include "core/interrupt.h"
#include "core/log.h"
#include "core/progress.h"
#include "io/image/png_io.h"
#include "io/point_io.h"
#include "render/archive_pack.h"
#include "render/synthetic_scene.h"

namespace candi::bench {

namespace {

namespace fs = std::filesystem;

// The render's own time ("..., 1234 ms, ...") from `candi render`'s summary line.
double RenderMs(const std::string& out) {
  const size_t at = out.find(" ms,");
  if (at == std::string::npos) return -1;
  size_t begin = out.rfind(' ', at - 1);
  return std::stod(out.substr(begin + 1, at - begin - 1));
}

bool SamePixels(const std::string& a, const std::string& b) {
  const io::PngImage x = io::ReadPng(a), y = io::ReadPng(b);
  return x.image16.width() == y.image16.width() && x.image16.height() == y.image16.height() &&
         std::memcmp(x.image16.data(), y.image16.data(), sizeof(uint16_t) * x.image16.width() * x.image16.height() * 3) == 0;
}

// Writes n generated points (pieces of 1e6 with their own seeds) as binary PLY, float positions,
// and flushes it to disk.
void WriteScene(const std::string& path, uint64_t n) {
  constexpr uint64_t kPiece = 1000000;
  io::PointWriteSpec spec;
  spec.schema.colors = true;
  spec.schema.position_type = ScalarType::kFloat32;
  spec.count = n;
  io::PointWriteOptions wo;
  wo.precision = io::PositionPrecision::kFloat32;
  auto writer = io::OpenPointWriter(path, spec, wo);
  ConsoleProgress progress("bench scale: writing " + path);
  for (uint64_t k = 0; k * kPiece < n; ++k) {
    PointCloud piece = render::TerracedSolid(std::min(kPiece, n - k * kPiece), 1000 + k);
    piece.schema.position_type = ScalarType::kFloat32;
    writer->Write(piece);
    progress.Update(std::min(n, (k + 1) * kPiece), n);
  }
  writer->Close();
  progress.Finish();
  // On disk before the timed pack, so its writeback does not run during the pack (which then
  // reads a file at rest from the page cache, as a file packed after it was made would be).
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0 || fsync(fd) != 0) LogWarning(path + ": cannot flush it to disk: " + std::strerror(errno));
  if (fd >= 0) close(fd);
}

}  // namespace

void ScaleBenchOptions::Check() const {
  CANDI_CHECK_OPTION_IN(repeat_level, 1, 100000);
  CANDI_CHECK_OPTION_IN(ranks, 0, 64);
}

int RunScaleBench(const ScaleBenchOptions& args) {
  args.Check();
  const std::vector<uint64_t> sizes = ParseBenchSizes(args.sizes, args.billion);
  const std::string self = SelfPath();
  const std::string dir = fs::absolute(args.work_dir).string();
  fs::create_directories(dir);
  const long cores = sysconf(_SC_NPROCESSORS_ONLN);
  std::printf("candi bench scale: terraced solid, %s, L = %d, %ld core(s); pack from binary PLY (1e9: from the "
              "generator), render from the archive; peak RSS per process\n",
              args.size.c_str(), args.repeat_level, cores);
  std::printf("%12s %9s %10s %9s %10s %10s %11s %10s %10s %11s %9s\n", "points", "pack s", "pack Mpt/s", "GB",
              "render s", "Mpt/s", "peak MB", "np s", "np Mpt/s", "np peak MB", "np same");
  std::fflush(stdout);
  int failures = 0;
  for (uint64_t n : sizes) {
    const std::string ply = dir + "/scene.ply", archive = dir + "/scene.archive";
    std::vector<std::string> pack = {self, "-q", "pack", "-o", archive};
    if (n <= 200000000ULL) {
      WriteScene(ply, n);
      pack.push_back(ply);
    }
    ChildRun packed;
    if (n <= 200000000ULL) {
      packed = RunChild(pack);
    } else {
      // 1e9: pack in this process straight from the generator (a PLY would take 15 GB).
      const auto start = std::chrono::steady_clock::now();
      render::PackOptions o;
      ConsoleProgress progress("bench scale: packing");
      render::PackArchive(o,
                          {render::PackInputFromGenerator("terraced solid", n, 1000000,
                                                          [](uint64_t k, uint64_t m) {
                                                            return render::TerracedSolid(m, 1000 + k);
                                                          })},
                          archive, progress.Callback());
      progress.Finish();
      packed.code = 0;
      packed.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    std::error_code ec;
    if (!args.keep) fs::remove(ply, ec);
    if (packed.code != 0) {
      std::printf("%12llu pack failed (exit %d)\n", static_cast<unsigned long long>(n), packed.code);
      ++failures;
      continue;
    }
    uint64_t bytes = 0;
    for (const auto& e : fs::directory_iterator(archive)) bytes += e.file_size();
    const std::string budget = std::to_string(1500);
    const std::vector<std::string> render = {"render", archive, "-o", dir + "/one.png", "--png16", dir + "/one16.png",
                                             "--size", args.size, "-L", std::to_string(args.repeat_level),
                                             "--memory-budget", budget};
    std::vector<std::string> one = {self, "-q"};
    one.insert(one.end(), render.begin(), render.end());
    const ChildRun r1 = RunChild(one);
    ChildRun rk;
    bool same = false;
    if (args.ranks > 0) {
      std::vector<std::string> mpi = {"mpirun", "--oversubscribe", "-np", std::to_string(args.ranks)};
      if (geteuid() == 0) mpi.push_back("--allow-run-as-root");
      mpi.push_back(self);
      mpi.push_back("-q");
      std::vector<std::string> rr = render;
      rr[3] = dir + "/np.png";
      rr[5] = dir + "/np16.png";
      mpi.insert(mpi.end(), rr.begin(), rr.end());
      mpi.push_back("--threads");
      mpi.push_back(std::to_string(std::max<long>(1, cores / args.ranks)));
      rk = RunChild(mpi);
      same = r1.code == 0 && rk.code == 0 && SamePixels(dir + "/one16.png", dir + "/np16.png");
    }
    const double s1 = RenderMs(r1.out) / 1000, sk = RenderMs(rk.out) / 1000;
    std::printf("%12llu %9.1f %10.1f %9.2f %10.2f %10.1f %11.0f %10.2f %10.1f %11.0f %9s\n",
                static_cast<unsigned long long>(n), packed.seconds, n / packed.seconds / 1e6, bytes / 1e9, s1,
                n / s1 / 1e6, r1.peak_mb, sk, args.ranks ? n / sk / 1e6 : 0.0, rk.peak_mb,
                args.ranks ? (same ? "yes" : "NO") : "-");
    std::printf("%12s (wall: render %.2f s, mpirun %.2f s, incl. start-up and PNG; CPU: pack %.1f s, render %.1f s, "
                "mpirun %.1f s; on a busy machine CPU seconds are the fairer measure)\n",
                "", r1.seconds, rk.seconds, packed.cpu_seconds, r1.cpu_seconds, rk.cpu_seconds);
    std::fflush(stdout);
    if (r1.code != 0 || (args.ranks > 0 && (rk.code != 0 || !same))) ++failures;
    if (!args.keep) fs::remove_all(archive, ec);
    for (const char* f : {"/one.png", "/one16.png", "/np.png", "/np16.png"}) fs::remove(dir + f, ec);
  }
  std::error_code ignored;
  if (!args.keep) fs::remove_all(dir, ignored);
  return failures ? 2 : 0;  // 2: a run failed or the ranks' image differed (as bad input)
}

}  // namespace candi::bench

// candi bench view: what a page of `candi view` gets from the server's renderer on generated
// archives (the terraced solid of bench scale) of 1e7, 1e8 (1e9) points: during an orbit, the
// latency of the first frame after each camera change (render, average, JPEG) and the frames per
// second; at rest, the time until the L-ensemble image is converged and sent (PNG); peak memory.
// The schedule is the server's (view::StepPolicy); the socket is left out (127.0.0.1 adds well
// under a millisecond a frame).
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <vector>

#include "bench/archives.h"
#include "bench/bench.h"
#include "core/check.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "core/timer.h"
#include "io/image/jpeg_io.h"
#include "io/image/png_io.h"
#include "render/archive.h"
#include "render/archive_pack.h"
#include "render/synthetic_scene.h"
#include "view/progressive.h"
#include "view/source.h"

namespace candi::bench {

namespace {

namespace fs = std::filesystem;

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t k = static_cast<size_t>(std::min<double>(v.size() - 1, std::ceil(q * v.size()) - 1));
  return v[k];
}

double PeakMb() {
  struct rusage u {};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;
}

}  // namespace

void ViewBenchOptions::Check() const {
  CANDI_CHECK_OPTION_IN(repeat_level, 1, 100000);
  CANDI_CHECK_OPTION_IN(threads, 0, 256);
  CANDI_CHECK_OPTION_GE(orbit_frames, 1);
  CANDI_CHECK_OPTION_IN(runs, 1, 100);
}

int RunViewBench(const ViewBenchOptions& args) {
  args.Check();
  const std::vector<uint64_t> sizes = ParseBenchSizes(args.sizes, args.billion);
  int width = 0, height = 0;
  {
    const std::vector<double> v = ParseNumbers(args.size, 'x', "--size");
    if (v.size() != 2 || v[0] < 16 || v[1] < 16 || v[0] > 4096 || v[1] > 4096) {
      throw std::invalid_argument("--size '" + args.size + "': expected WxH in [16, 4096]");
    }
    width = static_cast<int>(v[0]), height = static_cast<int>(v[1]);
  }
  if (args.repeat_level < 1 || args.repeat_level > view::kMaxViewRepeatLevel) {
    throw std::invalid_argument("-L: in [1, 10000]");
  }
  if (args.orbit_frames < 2) throw std::invalid_argument("--orbit-frames: at least 2");
  const std::string dir = fs::absolute(args.work_dir).string();
  fs::create_directories(dir);
  std::printf("candi bench view: terraced solid, %dx%d, L = %d, %d thread(s) (0: all); orbit of %d camera changes, "
              "first frame = render + average + JPEG; converged = every step to L + PNG; median of %d\n",
              width, height, args.repeat_level, args.threads, args.orbit_frames, args.runs);
  std::printf("%12s %8s %9s %9s %9s %8s %8s %11s %9s\n", "points", "pack s", "p50 ms", "p95 ms", "frames/s",
              "ensembl.", "conv. s", "conv. steps", "peak MB");
  std::fflush(stdout);
  const view::StepPolicy policy;
  for (uint64_t n : sizes) {
    double pack_s = 0;
    const std::string archive_dir = BenchArchive(dir, n, args.keep, "bench view", &pack_s);
    const render::Archive archive(archive_dir);
    const render::ArchiveManifest& m = archive.manifest();
    const Box3d world = m.bounds.Translated(m.frame.origin);
    view::ViewState state;
    state.camera = render::FirstView(world, width, height, render::Orientation());
    state.settings.spbr.repeat_level = args.repeat_level;
    view::ProgressiveImage image(archive, view::LocalRangeRenderer(archive), args.threads);

    // The orbit: the camera turns by 3 degrees a frame; each frame is the first step of its image.
    std::vector<double> latency, ensembles;
    const Eigen::Vector3d target = state.camera.target, arm = state.camera.eye - target;
    double orbit_ms = 0;
    for (int f = 0; f < args.orbit_frames; ++f) {
      const double angle = 3.0 * f * 3.14159265358979 / 180;
      const Eigen::Vector3d turned(std::cos(angle) * arm.x() - std::sin(angle) * arm.y(),
                                   std::sin(angle) * arm.x() + std::cos(angle) * arm.y(), arm.z());
      state.camera.eye = target + turned;
      const Stopwatch watch;
      image.Start(state);
      const int count = policy.Ensembles(image.ms_per_ensemble(), 0);
      image.Step(count);
      const std::string jpeg = io::EncodeJpeg(image.Image(nullptr), 85);
      const double ms = 1000 * watch.Seconds();
      orbit_ms += ms;
      if (f > 0) latency.push_back(ms), ensembles.push_back(count);  // the first frame sets the rate
    }
    // At rest: from a camera change to the converged PNG, every step's frame encoded.
    std::vector<double> converge, steps;
    for (int r = 0; r < args.runs; ++r) {
      const Stopwatch watch;
      image.Start(state);
      int step = 0;
      while (!image.converged()) {
        image.Step(policy.Ensembles(image.ms_per_ensemble(), step++));
        const Image8 pixels = image.Image(nullptr);
        if (image.converged()) io::EncodePng(pixels, {}, io::PngCompression::kFast); else io::EncodeJpeg(pixels, 85);
      }
      converge.push_back(watch.Seconds());
      steps.push_back(step);
    }
    std::printf("%12llu %8.1f %9.1f %9.1f %9.1f %8.0f %8.2f %11.0f %9.0f\n", static_cast<unsigned long long>(n),
                pack_s, Percentile(latency, 0.5), Percentile(latency, 0.95),
                1000.0 * args.orbit_frames / orbit_ms, Percentile(ensembles, 0.5), Percentile(converge, 0.5),
                Percentile(steps, 0.5), PeakMb());
    std::fflush(stdout);
    std::error_code ec;
    if (!args.keep) fs::remove_all(archive_dir, ec);
  }
  std::error_code ignored;
  if (!args.keep) fs::remove_all(dir, ignored);
  return 0;
}

}  // namespace candi::bench

// candi bench publish: candi publish on generated archives (bench/bench.h).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/archives.h"
#include "bench/bench.h"
#include "core/check.h"
#include "core/text_format.h"
#include "render/first_view.h"
#include "view/publish.h"

namespace candi::bench {

namespace fs = std::filesystem;

void PublishBenchOptions::Check() const {
  CANDI_CHECK_OPTION_IN(repeat_level, 1, 1000);
  CANDI_CHECK_OPTION_IN(runs, 1, 100);
}

int RunPublishBench(const PublishBenchOptions& a) {
  a.Check();
  const std::vector<uint64_t> sizes = ParseBenchSizes(a.sizes, a.billion);
  std::vector<int> threads;
  for (double v : ParseNumbers(a.threads, ',', "--threads")) {
    if (!(v >= 1 && v <= 256)) throw std::invalid_argument("--threads: each in [1, 256]");
    threads.push_back(static_cast<int>(v));
  }
  const std::string dir = fs::absolute(a.work_dir).string();
  fs::create_directories(dir);
  std::printf("candi bench publish: L = %d pages, median of %d run(s); the terraced solid (shaded colours)\n",
              a.repeat_level, a.runs);
  std::printf("%12s %7s %9s %10s %11s %14s %12s %16s\n", "points", "threads", "seconds", "M points/s",
              "bytes/point", "first image MB", "data MB", "points/ensemble");
  for (uint64_t n : sizes) {
    double pack_s = 0;
    const std::string archive_dir = BenchArchive(dir, n, a.keep, "bench publish", &pack_s);
    const std::string site = dir + "/site-" + std::to_string(n);
    for (int t : threads) {
      view::PublishOptions o;
      o.repeat_level = a.repeat_level;
      o.threads = t;
      std::vector<double> seconds;
      view::PublishStats stats;
      for (int r = 0; r < a.runs; ++r) {
        stats = view::PublishSite(o, archive_dir, site, render::Orientation());
        seconds.push_back(stats.seconds);
      }
      std::sort(seconds.begin(), seconds.end());
      const double median = seconds[seconds.size() / 2];
      std::printf("%12llu %7d %9.2f %10.1f %11.2f %14.2f %12.1f %16llu\n", static_cast<unsigned long long>(n), t,
                  median, n / median * 1e-6, stats.BytesPerPoint(), stats.first_image_bytes * 1e-6,
                  stats.data_bytes * 1e-6, static_cast<unsigned long long>(n / a.repeat_level));
      std::fflush(stdout);
    }
    if (!a.keep) {
      fs::remove_all(archive_dir);
      fs::remove_all(site);
    }
  }
  std::printf("\nThe archive itself stores 8 bytes a point; COPC about 5. An ensemble draws points/ensemble "
              "GL_POINTS; a GPU's published rate for them gives its frame time.\n");
  return 0;
}

}  // namespace candi::bench

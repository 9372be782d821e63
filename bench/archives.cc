#include "bench/archives.h"

#include <chrono>
#include <stdexcept>

#include "core/progress.h"
#include "core/text_format.h"
#include "render/archive.h"
#include "render/archive_pack.h"
#include "render/synthetic_scene.h"

namespace candi::bench {

std::vector<uint64_t> ParseBenchSizes(const std::string& text, bool billion) {
  std::vector<uint64_t> sizes;
  for (double v : ParseNumbers(text, ',', "--sizes")) {
    if (!(v >= 1000 && v <= 1e10)) throw std::invalid_argument("--sizes: each count in [1e3, 1e10]");
    sizes.push_back(static_cast<uint64_t>(v));
  }
  if (billion) sizes.push_back(1000000000ULL);
  return sizes;
}

std::string BenchArchive(const std::string& dir, uint64_t n, bool keep, const std::string& what, double* pack_seconds) {
  const std::string archive_dir = dir + "/scene-" + std::to_string(n) + ".archive";
  *pack_seconds = 0;
  if (keep && render::IsArchive(archive_dir)) {  // kept by an earlier --keep run
    try {
      if (render::Archive(archive_dir).manifest().points == n) return archive_dir;
    } catch (const std::exception&) {
    }
  }
  const auto start = std::chrono::steady_clock::now();
  ConsoleProgress progress(what + ": packing " + std::to_string(n) + " points");
  render::PackArchive(render::PackOptions(),
                      {render::PackInputFromGenerator("terraced solid", n, 1000000,
                                                      [](uint64_t k, uint64_t m) {
                                                        return render::TerracedSolid(m, 1000 + k);
                                                      })},
                      archive_dir, progress.Callback());
  progress.Finish();
  *pack_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return archive_dir;
}

}  // namespace candi::bench

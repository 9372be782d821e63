// candi pack IN... -o ARCHIVE: point files to a render archive (render/archive.h), streaming.
#include <algorithm>
#include <cstdio>
#include <stdexcept>

#include "apps/commands.h"
#include "core/log.h"
#include "core/progress.h"
#include "render/archive_pack.h"

namespace candi::app {

int RunPack(const PackArgs& args) {
  if (!(args.memory_mb > 0)) throw std::invalid_argument("--memory must be > 0 MB");
  render::PackOptions o;
  o.chunk_points = args.chunk_points;
  o.memory_points = std::max<uint64_t>(o.chunk_points, static_cast<uint64_t>(args.memory_mb * 1048576.0 / 100));
  o.threads = args.threads;
  std::vector<render::PackInput> inputs;
  for (const std::string& in : args.inputs) {
    inputs.push_back(render::PackInputFromFile(in, args.columns));
  }
  ConsoleProgress progress("pack");
  const render::PackSummary s = render::PackArchive(o, inputs, args.output, progress.Callback());
  progress.Finish();
  std::printf("%s: %llu points in %llu chunks, %llu data file(s), %.2f bytes/point, %.1f s (%.1f M points/s: "
              "bounds %.1f s, sort and write %.1f s; input hashes %.1f s during the bounds)%s, %zu-byte records; "
              "largest quantization error %.3g, %.3g, %.3g mm\n",
              args.output.c_str(), static_cast<unsigned long long>(s.points),
              static_cast<unsigned long long>(s.chunks), static_cast<unsigned long long>(s.files),
              s.points ? static_cast<double>(s.bytes) / s.points : 0.0, s.seconds, s.points / s.seconds / 1e6,
              s.bounds_seconds, s.sort_seconds, s.hash_seconds, s.spilled_points ? ", sorted on disk" : "",
              s.record_bytes, 1e3 * s.max_error[0], 1e3 * s.max_error[1], 1e3 * s.max_error[2]);
  return kOk;
}

}  // namespace candi::app

// candi opacity IN OUT: SPBR point-number adjustment (sampling/opacity.h) from file to file.
// Writes the kept points with the field spbr_multiplicity, records the parameters as a comment
// ("candi_opacity alpha=... repeat_level=... pixel_size=... seed=..."), prints a summary table.
#include <cstdio>
#include <string>

#include "apps/commands.h"
#include "apps/output_folder.h"
#include "core/check.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "io/point_io.h"
#include "sampling/opacity.h"

namespace candi::app {

namespace {

sampling::OpacityOptions Options(const OpacityArgs& args) {
  sampling::OpacityOptions o;
  o.alpha = args.alpha;
  o.repeat_level = args.repeat_level;
  o.image_size = args.image_size;
  o.pixel_size = args.pixel_size;
  o.seed = args.seed;
  o.density.method = sampling::ParseDensityMethod(args.method);
  o.density.target_neighbours = args.neighbours;
  o.density.radius = args.radius;
  o.density.seed = args.seed;
  o.density.threads = args.threads;
  o.Check();
  return o;
}

std::string Comment(const sampling::OpacityOptions& o, const sampling::OpacitySummary& s) {
  return "candi_opacity alpha=" + FormatDouble(o.alpha) +
         " repeat_level=" + std::to_string(o.repeat_level) +
         " pixel_size=" + FormatDouble(s.pixel_size) +
         (o.image_size > 0 ? " image_size=" + std::to_string(o.image_size) : std::string()) +
         " seed=" + std::to_string(o.seed) + " method=" + sampling::DensityMethodName(o.density.method) +
         " radius=" + FormatDouble(s.radius);
}

std::string Percent(size_t part, size_t whole) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.1f %%", whole ? 100.0 * part / whole : 0.0);
  return buf;
}

void PrintSummary(const sampling::OpacityOptions& o, const sampling::OpacitySummary& s) {
  std::printf("points in        %zu\n", s.points_in);
  std::printf("points out       %zu\n", s.points_out);
  std::printf("copies drawn     %llu (sum of spbr_multiplicity)\n",
              static_cast<unsigned long long>(s.total_copies));
  std::printf("removed          %zu (%s)\n", s.removed, Percent(s.removed, s.points_in).c_str());
  std::printf("replicated       %zu (%s)\n", s.replicated,
              Percent(s.replicated, s.points_in).c_str());
  std::printf("capped at L=%-5d %zu (%s)\n", o.repeat_level, s.capped,
              Percent(s.capped, s.points_in).c_str());
  std::printf("ratio n'/n       min %.4g  median %.4g  max %.4g\n", s.ratio_min, s.ratio_median,
              s.ratio_max);
  std::printf("pixel size       %.6g m  (s/S = %.4g, S = %.6g m^2, radius %.6g m)\n", s.pixel_size,
              s.point_area_ratio, s.area, s.radius);
  std::printf("median density   %.6g points/m^2\n", s.median_density);
  std::printf("target alpha     %.4g\n", o.alpha);
  std::printf("predicted alpha  %.4g (at the median density)\n", s.predicted_alpha);
  if (!s.message.empty()) std::printf("note             %s\n", s.message.c_str());
}

}  // namespace

int RunOpacity(const OpacityArgs& args) {
  sampling::OpacityOptions options = Options(args);  // bad values: std::invalid_argument, exit 1
  io::OutputPointFormat(args.output);  // a known extension, and a writable folder, before the work
  CheckOutputFolder(args.output);
  const PointCloud cloud = io::ReadPointCloud(args.input);
  ConsoleProgress progress("opacity: density of " + args.input);
  options.density.progress = progress.Callback();
  sampling::OpacityResult result = sampling::AdjustOpacity(options, cloud);
  progress.Finish();
  result.cloud.meta.comments.push_back(Comment(options, result.summary));
  io::WritePointCloud(args.output, result.cloud);
  PrintSummary(options, result.summary);
  return kOk;
}

}  // namespace candi::app

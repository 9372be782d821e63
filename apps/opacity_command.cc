// candi opacity: SPBR opacity by point-number adjustment from file to file (sampling/opacity.h;
// writes the kept points with the field spbr_multiplicity and records the parameters as a comment
// "candi_opacity alpha=... repeat_level=... pixel_size=... seed=...").
#include <cstdio>
#include <string>

#include "apps/arg_parse.h"
#include "apps/commands.h"
#include "apps/failure.h"
#include "core/atomic_file.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "io/point_io.h"
#include "sampling/opacity.h"

namespace candi::apps {

namespace {

std::string Comment(const sampling::OpacityOptions& o, const sampling::OpacitySummary& s) {
  return "candi_opacity alpha=" + FormatDouble(o.alpha) +
         " repeat_level=" + std::to_string(o.spbr.repeat_level) +
         " pixel_size=" + FormatDouble(s.pixel_size) +
         (o.image_size > 0 ? " image_size=" + std::to_string(o.image_size) : std::string()) +
         " seed=" + std::to_string(o.spbr.seed) + " method=" + sampling::DensityMethodName(o.density.method) +
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
  std::printf("capped at L=%-5d %zu (%s)\n", o.spbr.repeat_level, s.capped,
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

struct OpacityArgs {
  std::string input, output;
  sampling::OpacityOptions options;  // alpha and repeat_level are required
};

int RunOpacity(const OpacityArgs& args) {
  sampling::OpacityOptions options = args.options;
  options.density.seed = options.spbr.seed;
  options.Check();  // bad values: std::invalid_argument, exit 1
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

}  // namespace

void AddOpacity(Command& root) {
  OpacityArgs& a = root.Keep<OpacityArgs>();
  sampling::OpacityOptions& o = a.options;
  o.image_size = 0;  // no default on the command line: exactly one of --image-size and --pixel-size
  Command c = root.Add("opacity", "Set SPBR opacity by point-number adjustment: removes or replicates points (field "
                                  "spbr_multiplicity) for a target alpha");
  c.Option("input", a.input, "Input point file").Required();
  c.Option("output", a.output, "Output point file; format from its extension").Required();
  c.Option("--alpha", o.alpha, "Target opacity, 0..1").Required();
  c.Option("--repeat-level", o.spbr.repeat_level, "L, the number of ensembles the renderer averages").Required();
  c.Option("--image-size", o.image_size, "Pixels across the cloud's largest extent");
  c.Option("--pixel-size", o.pixel_size, "Or: the pixel footprint's side, metres");
  c.Option("--seed", o.spbr.seed, "Random seed");
  Arg k = c.Option("--neighbours", o.density.target_neighbours, "Neighbours of the median point for the automatic "
                   "density radius (default 32)");
  c.Option("--radius", o.density.radius, "Density radius, metres (default: automatic)").Excludes(k);
  c.Choice("--method", o.density.method,
           {{"kdtree", sampling::DensityMethod::kKdTree}, {"voxel", sampling::DensityMethod::kVoxel}},
           "Density estimate: kdtree or voxel");
  c.Option("--threads", o.density.threads, "Worker threads (0 = all)");
  c.Run([&a] { return RunOpacity(a); });
  c.Footer("Example: candi opacity site.ply site_a05.ply --alpha 0.5 --repeat-level 100 --image-size 1024");
}

}  // namespace candi::apps

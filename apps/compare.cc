// candi compare: the deviation of one cloud from a reference cloud or mesh (pipeline/compare.h):
// the distance per point as a scalar field, a summary, a histogram and a report.
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

#include "apps/commands.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "pipeline/compare.h"

namespace candi::apps {

namespace {

struct CompareArgs {
  std::string reference, compared, output;
  pipeline::CompareOptions options;
};

int RunCompare(const CompareArgs& args) {
  std::optional<ConsoleProgress> progress;
  const pipeline::CompareOutcome out = pipeline::RunCompare(
      args.options, args.reference, args.compared, args.output, [&](uint64_t done, uint64_t total) {
        if (!progress) progress.emplace(compare::MethodName(args.options.deviation.method) + " " +
                                        args.compared);
        progress->Update(done, total);
      });
  if (progress) progress->Finish();
  const compare::DeviationSummary& s = out.summary;
  auto mm = [](double m) { return std::isnan(m) ? std::string("n/a") : FormatSignificant(m * 1000, 5) + " mm"; };
  std::printf("%-22s %s\n", "method", compare::MethodName(s.method).c_str());
  std::printf("%-22s %llu (%llu undefined)\n", "points",
              static_cast<unsigned long long>(s.count), static_cast<unsigned long long>(s.undefined));
  std::printf("%-22s %s\n", "mean", mm(s.mean).c_str());
  std::printf("%-22s %s\n", "std", mm(s.std).c_str());
  std::printf("%-22s %s\n", "rms", mm(s.rms).c_str());
  if (!s.percentiles.empty()) {
    std::printf("%-22s %s / %s / %s\n", "p5 / median / p95", mm(s.percentiles[1].second).c_str(),
                mm(s.percentiles[3].second).c_str(), mm(s.percentiles[5].second).c_str());
  }
  std::printf("%-22s %s\n", ("within " + mm(s.tolerance)).c_str(),
              s.defined ? (FormatSignificant(100 * s.within_tolerance, 4) + " %").c_str() : "n/a");
  if (s.method == compare::Method::kM3C2) {
    std::printf("%-22s %llu\n", "significant change", static_cast<unsigned long long>(s.significant));
  }
  for (const std::string& w : out.result.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
  std::printf("wrote %s, %s, %s, %s\n", out.cloud.c_str(), out.json.c_str(), out.histogram.c_str(),
              out.report.c_str());
  return kOk;
}

}  // namespace

void AddCompare(Command& root) {
  CompareArgs& a = root.Keep<CompareArgs>();
  compare::DeviationOptions& d = a.options.deviation;
  Command c = root.Add("compare", "Deviation of COMPARED from REFERENCE (C2C, C2M, M3C2, as CloudCompare): the "
                                  "distance per point as a scalar field, a summary, a histogram and a report");
  c.Option("reference", a.reference, "Reference point file (C2C, M3C2) or mesh, PLY or OBJ (C2M)").Required();
  c.Option("compared", a.compared, "Compared point file: one distance per point, in its order").Required();
  c.Option("-o,--output", a.output,
           "Output point file (format by extension; PLY and LAS keep the fields); also writes "
           "OUT.compare.json, OUT.histogram.svg and OUT.report.md").Required();
  c.Choice("--method", d.method,
           {{"c2c", compare::Method::kC2C}, {"c2m", compare::Method::kC2M}, {"m3c2", compare::Method::kM3C2}},
           "c2c (nearest point), c2m (signed, to a mesh) or m3c2 (Lague et al. 2013)");
  c.Choice("--model", d.c2c.local_model,
           {{"none", compare::LocalModel::kNone}, {"plane", compare::LocalModel::kPlane},
            {"quadric", compare::LocalModel::kQuadric}},
           "C2C: a local model of the reference: none, plane or quadric (least squares)");
  c.Option("--model-neighbours", d.c2c.model_neighbours, "C2C: reference points a local model is fitted to");
  c.FlagOff("--unsigned", d.c2m.signed_distance, "C2M: |distance| instead of the signed distance");
  c.Option("--normal-scale", d.m3c2.normal_scale, "M3C2: D, the diameter normals are fitted over, m (0: 2 d)");
  c.Option("--projection-scale", d.m3c2.projection_scale,
           "M3C2: d, the cylinder's diameter, m (0: ~30 reference points in it)");
  c.Option("--max-depth", d.m3c2.max_depth, "M3C2: the cylinder's half-length, m (0: D)");
  c.Option("--registration-error", d.m3c2.registration_error, "M3C2: added to LoD95, m");
  c.Option("--min-points", d.m3c2.min_points, "M3C2: points each cloud needs in a cylinder");
  c.Choice("--orientation", d.m3c2.orientation,
           {{"+z", compare::NormalOrientation::kPlusZ}, {"-z", compare::NormalOrientation::kMinusZ},
            {"+x", compare::NormalOrientation::kPlusX}, {"-x", compare::NormalOrientation::kMinusX},
            {"+y", compare::NormalOrientation::kPlusY}, {"-y", compare::NormalOrientation::kMinusY},
            {"out", compare::NormalOrientation::kOutward}},
           "M3C2: normals towards +z (... -y), or out: away from the reference's centroid");
  c.Option("--tolerance", a.options.summary.tolerance, "Summary: |distance| within this counts as within, m");
  c.Option("--bins", a.options.summary.bins, "Histogram bins");
  c.Option("--range", a.options.summary.range, "Histogram range, m (signed: -range..range; 0: the 99th percentile)");
  c.Option("--columns", a.options.columns, "XYZ/PTS column spec of text inputs, e.g. x,y,z,r,g,b");
  c.Option("--threads", d.threads, "Threads (0: all); results do not depend on it").Range(0, 256);
  c.Run([&a] { return RunCompare(a); });
  c.Footer("Examples: candi compare scan2025.las scan2026.las -o change.las --method m3c2 --registration-error 0.003\n"
           "          candi compare wall_mesh.ply photogrammetry.ply -o deviation.ply --method c2m --tolerance 0.005");
}

}  // namespace candi::apps

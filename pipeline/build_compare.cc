// The scene's comparisons (pipeline/scene.h, "comparisons"), run by the build once the layers are
// written: each compared layer's file (layers/<name>.ply, world coordinates) against a reference
// layer's file or a reference file, through RunCompare (pipeline/compare.h), into compare/.
#include <cmath>
#include <string>

#include "core/check.h"
#include "core/log.h"
#include "core/progress.h"
#include "core/text_format.h"
#include "core/timer.h"
#include "pipeline/build_internal.h"
#include "pipeline/compare.h"

namespace candi::pipeline::internal {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A number for JSON: NaN (no distance defined) as null.
json Figure(double v) { return std::isfinite(v) ? json(v) : json(); }

const std::string& LayerFile(const Scene& scene, const std::vector<std::string>& layer_files, const std::string& name) {
  for (size_t k = 0; k < scene.layers.size(); ++k)
    if (scene.layers[k].name == name) return layer_files[k];
  throw InternalError("no layer named " + name);  // LoadScene checked every name
}

// What archive.json says of a comparison that has run: what was compared, how, where the files
// are (relative to archive.json) and the headline figures.
json Entry(const SceneComparison& c, const CompareOutcome& outcome) {
  const compare::DeviationSummary& s = outcome.summary;
  const std::string base = "compare/" + c.name + ".ply";
  json e = {{"name", c.name},
            {"compared", c.compared},
            {"reference", c.reference_layer.empty() ? c.reference_file : c.reference_layer},
            {"reference_kind", c.reference_layer.empty() ? "file" : "layer"},
            {"method", compare::MethodName(s.method)},
            {"signed", s.is_signed},
            {"files", {{"cloud", base}, {"summary", base + ".compare.json"}, {"histogram", base + ".histogram.svg"},
                       {"report", base + ".report.md"}}},
            {"count", s.count},
            {"defined", s.defined},
            {"undefined", s.undefined},
            {"mean_m", Figure(s.mean)},
            {"std_m", Figure(s.std)},
            {"rms_m", Figure(s.rms)},
            {"mean_abs_m", Figure(s.mean_abs)},
            {"tolerance_m", s.tolerance},
            {"within_tolerance", Figure(s.defined ? s.within_tolerance : NAN)}};
  if (s.method == compare::Method::kM3C2) e["significant"] = s.significant;
  return e;
}

// One comparison, or its checkpoint (key: its JSON, the bytes of both inputs).
json RunComparison(const BuildOptions& options, const Scene& scene, const json& comparison_json, const fs::path& out,
                   const Checkpoints& checkpoints, FileHashes& hashes, const std::vector<std::string>& layer_files,
                   const SceneComparison& c, double* seconds) {
  const std::string compared = LayerFile(scene, layer_files, c.compared);
  const std::string reference =
      c.reference_layer.empty() ? c.reference_file : LayerFile(scene, layer_files, c.reference_layer);
  const std::string key = Key({"comparison", comparison_json.dump(), hashes(compared), hashes(reference)});
  const std::string cloud = (out / "compare" / (c.name + ".ply")).string(), stage = "compare_" + c.name;
  const std::optional<json> checkpoint = checkpoints.Find(
      stage, key, {cloud, cloud + ".compare.json", cloud + ".histogram.svg", cloud + ".report.md"});
  if (checkpoint) {
    LogInfo("comparison " + c.name + ": resumed from " + cloud);
    *seconds = checkpoint->at("seconds").get<double>();
    json e = checkpoint->at("entry");
    e["resumed"] = true;
    return e;
  }
  LogInfo("comparison " + c.name + ": " + c.compared + " against " +
          (c.reference_layer.empty() ? c.reference_file : c.reference_layer) + " (" +
          compare::MethodName(c.deviation.method) + ")");
  const Stopwatch watch;
  CompareOptions o;
  o.deviation = c.deviation;
  o.deviation.threads = options.threads;  // the results do not depend on it
  o.summary = c.summary;
  ConsoleProgress progress("compare " + c.name);
  const CompareOutcome outcome = RunCompare(o, reference, compared, cloud, progress.Callback());
  progress.Finish();
  for (const std::string& w : outcome.result.warnings) LogWarning("comparison " + c.name + ": " + w);
  json e = Entry(c, outcome);
  *seconds = watch.Seconds();
  checkpoints.Save(stage, key, {{"entry", e}, {"seconds", *seconds}});
  e["resumed"] = false;
  return e;
}

}  // namespace

json RunComparisons(const BuildOptions& options, const Scene& scene, const json& scene_json, const fs::path& out,
                    const Checkpoints& checkpoints, FileHashes& hashes, const std::vector<std::string>& layer_files,
                    json* timings) {
  json list = json::array();
  if (scene.comparisons.empty()) return list;
  fs::create_directories(out / "compare");
  for (size_t i = 0; i < scene.comparisons.size(); ++i) {
    const SceneComparison& c = scene.comparisons[i];
    double seconds = 0;
    list.push_back(RunComparison(options, scene, scene_json["comparisons"][i], out, checkpoints, hashes, layer_files,
                                 c, &seconds));
    (*timings)["comparisons"][c.name] = seconds;
  }
  return list;
}

}  // namespace candi::pipeline::internal

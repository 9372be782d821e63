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

const std::string& LayerFile(const Scene& scene, const std::vector<std::string>& layer_files, const std::string& name) {
  for (size_t k = 0; k < scene.layers.size(); ++k)
    if (scene.layers[k].name == name) return layer_files[k];
  throw InternalError("no layer named " + name);  // LoadScene checked every name
}

// What archive.json says of a comparison that has run: what was compared, how, and the headline
// figures (its files are named by the comparison's name).
render::BuildComparisonRecord Entry(const SceneComparison& c, const CompareOutcome& outcome) {
  const compare::DeviationSummary& s = outcome.summary;
  render::BuildComparisonRecord e;
  e.name = c.name;
  e.compared = c.compared;
  e.reference = c.reference_layer.empty() ? c.reference_file : c.reference_layer;
  e.reference_is_layer = !c.reference_layer.empty();
  e.method = compare::MethodName(s.method);
  e.is_signed = s.is_signed;
  e.count = s.count;
  e.defined = s.defined;
  e.undefined = s.undefined;
  e.mean = s.mean;
  e.std = s.std;
  e.rms = s.rms;
  e.mean_abs = s.mean_abs;
  e.tolerance = s.tolerance;
  e.within_tolerance = s.defined ? s.within_tolerance : NAN;
  if (s.method == compare::Method::kM3C2) e.significant = s.significant;
  return e;
}

// One comparison, or its checkpoint (key: its JSON, the bytes of both inputs).
render::BuildComparisonRecord RunComparison(const BuildOptions& options, const Scene& scene,
                                            const fs::path& out, const Checkpoints& checkpoints,
                                            FileHashes& hashes,
                                            const std::vector<std::string>& layer_files,
                                            const SceneComparison& c, double* seconds) {
  const std::string compared = LayerFile(scene, layer_files, c.compared);
  const std::string reference =
      c.reference_layer.empty() ? c.reference_file : LayerFile(scene, layer_files, c.reference_layer);
  const std::string key = Key({"comparison", c.key_json, hashes(compared), hashes(reference)});
  const std::string cloud = (out / "compare" / (c.name + ".ply")).string(), stage = "compare_" + c.name;
  const std::optional<json> checkpoint = checkpoints.Find(
      stage, key, {cloud, cloud + ".compare.json", cloud + ".histogram.svg", cloud + ".report.md"});
  if (checkpoint) {
    LogInfo("comparison " + c.name + ": resumed from " + cloud);
    *seconds = checkpoint->at("seconds").get<double>();
    render::BuildComparisonRecord e = render::ComparisonFromJson(
        checkpoint->at("entry").dump(), (out / "work" / "checkpoints").string());
    e.resumed = true;
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
  const render::BuildComparisonRecord e = Entry(c, outcome);
  *seconds = watch.Seconds();
  checkpoints.Save(stage, key,
                   {{"entry", json::parse(render::ComparisonToJson(e))}, {"seconds", *seconds}});
  return e;
}

}  // namespace

std::vector<render::BuildComparisonRecord> RunComparisons(
    const BuildOptions& options, const Scene& scene, const fs::path& out,
    const Checkpoints& checkpoints, FileHashes& hashes, const std::vector<std::string>& layer_files,
    json* timings) {
  std::vector<render::BuildComparisonRecord> list;
  if (scene.comparisons.empty()) return list;
  fs::create_directories(out / "compare");
  for (size_t i = 0; i < scene.comparisons.size(); ++i) {
    const SceneComparison& c = scene.comparisons[i];
    double seconds = 0;
    list.push_back(
        RunComparison(options, scene, out, checkpoints, hashes, layer_files, c, &seconds));
    (*timings)["comparisons"][c.name] = seconds;
  }
  return list;
}

}  // namespace candi::pipeline::internal

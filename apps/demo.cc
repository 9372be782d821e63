// candi demo (candi-relief only): the bundled Borobudur example's site (pipeline/demo_site.h)
// built through pipeline/build.h, its relief panels predicted in this process (libtorch loads
// once), and the main renders copied beside the scene.
#include <cstdio>
#include <filesystem>

#include "apps/commands.h"
#include "core/timer.h"
#include "pipeline/build.h"
#include "pipeline/relief.h"
#include "pipeline/scene.h"

namespace candi::apps {

int RunDemo(const DemoArgs& a) {
  namespace fs = std::filesystem;
  const Stopwatch watch;
  const std::string scene_file = pipeline::MakeDemoSite(a.site, a.output_dir);
  const fs::path out = fs::path(scene_file).parent_path();
  pipeline::BuildOptions build;
  build.output = (out / "archive").string();
  build.relief = pipeline::ReliefInProcess();
  PrintBuildSummary(build.output, pipeline::Build(build, pipeline::LoadScene(scene_file)));
  for (const char* v : {"overview_opaque", "overview_transparent", "corner_opaque", "corner_transparent", "corner_panels"}) {
    std::error_code ec;
    fs::copy_file(out / "archive" / "renders" / (std::string(v) + ".png"), out / (std::string(v) + ".png"),
                  fs::copy_options::overwrite_existing, ec);
  }
  std::printf("demo: %s (scene %s), %.1f s\n", out.string().c_str(), scene_file.c_str(), watch.Seconds());
  return kOk;
}

}  // namespace candi::apps

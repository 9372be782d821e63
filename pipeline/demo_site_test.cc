#include "pipeline/demo_site.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/check.h"
#include "pipeline/scene.h"
#include "tests/util/option_check.h"
#include "tests/util/test_util.h"

namespace candi::pipeline {
namespace {

using testing::ExpectEachBreakRejected;
using testing::TempDir;

TEST(DemoSiteOptions, DefaultsPassAndQuickExcludesFull) {
  ExpectEachBreakRejected<DemoSiteOptions>({}, {
      [](DemoSiteOptions& o) { o.quick = o.full = true; },
      [](DemoSiteOptions& o) { o.width = 8; },
  });
}

// The quick site: every input written, and a scene file that loads with its four layers.
TEST(MakeDemoSite, TheQuickSitesInputsAndItsScene) {
  TempDir dir;
  DemoSiteOptions o;
  o.quick = true;
  o.width = 160;
  o.height = 120;
  const std::string scene_file = MakeDemoSite(o, dir.File("site"));
  EXPECT_EQ(scene_file, std::filesystem::absolute(dir.File("site/scene.json")).lexically_normal().string());
  const Scene scene = LoadScene(scene_file);
  ASSERT_EQ(scene.layers.size(), 4u);
  EXPECT_EQ(scene.layers[0].kind, LayerKind::kPoints);
  EXPECT_EQ(scene.layers[1].kind, LayerKind::kFoundation);
  EXPECT_EQ(scene.layers[2].kind, LayerKind::kRelief);
  EXPECT_EQ(scene.layers[2].panels.size(), 12u);  // 8 hidden and 4 visible
  EXPECT_EQ(scene.layers[3].kind, LayerKind::kPhotogrammetry);
  EXPECT_EQ(scene.views.size(), 7u);
  EXPECT_EQ(scene.render.spbr.repeat_level, 32);
  EXPECT_EQ(scene.render.width, 160);
  for (const std::string& f : scene.layers[3].Sources()) EXPECT_TRUE(testing::FileExists(f)) << f;
}

}  // namespace
}  // namespace candi::pipeline

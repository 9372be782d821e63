// `candi demo --quick`: the reduced Borobudur example end to end (what `make demo` runs, smaller).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "core/png_io.h"
#include "tests/run_candi.h"
#include "tests/util/test_util.h"

namespace candi {
namespace {

using testing::RunCandi;
using testing::TempDir;

TEST(DemoCli, QuickDemoBuildsTheExampleAndItsRenders) {
  TempDir dir;
  const testing::CommandResult r = RunCandi("-q demo --quick --width 160 --height 120 -o " + dir.File("demo"));
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json a = nlohmann::json::parse(testing::ReadBytes(dir.File("demo/archive/archive.json")));
  ASSERT_GE(a["layers"].size(), 2u);
  EXPECT_EQ(a["layers"][0]["name"], "building");
  EXPECT_EQ(a["layers"][1]["name"], "foundation");
  EXPECT_EQ(a["layers"][1]["points"], 200000);
  EXPECT_EQ(a["layers"][1]["scanned"], false);
  for (const char* v : {"overview_opaque", "overview_transparent", "corner_opaque", "corner_transparent"}) {
    SCOPED_TRACE(v);
    const PngImage png = ReadPng(dir.File(std::string("demo/") + v + ".png"));
    EXPECT_EQ(png.image8.width(), 160);
    // Something was drawn: not every pixel is the white background.
    size_t drawn = 0;
    for (size_t i = 0; i + 2 < png.image8.values().size(); i += 3)
      drawn += png.image8.values()[i] < 250 || png.image8.values()[i + 1] < 250 || png.image8.values()[i + 2] < 250;
    EXPECT_GT(drawn, 500u);
  }
  EXPECT_TRUE(testing::FileExists(dir.File("demo/scene.json")));
  EXPECT_NE(r.out.find("foundation"), std::string::npos) << r.out;  // the layer table
}

}  // namespace
}  // namespace candi

#include "render/view_json.h"

#include <gtest/gtest.h>

#include <stdexcept>

namespace candi::render {
namespace {

// A page's saved view: the camera, and under "settings" the layers' shares and the clipping.
TEST(ViewJson, ReadsAPagesSharesAndClipping) {
  const std::string text = R"({"projection": "perspective", "width": 64, "height": 48, "eye": [0, -10, 0],
    "target": [0, 0, 0], "up": [0, 0, 1], "settings": {"repeat_level": 20, "seed": 1, "brightness": "none",
    "layers": [0.5, 0, 2], "layer_names": ["a", "b", "c"], "clip": [[0, 0, 0, 1, 0, 0]]}})";
  SavedViewSettings s;
  const Camera c = ParseView(text, "view.json", &s);
  EXPECT_EQ(c.width, 64);
  ASSERT_EQ(s.layer_names.size(), 3u);
  EXPECT_EQ(s.layer_names[2], "c");
  EXPECT_EQ(s.layer_shares[0], 0.5);
  EXPECT_EQ(s.layer_shares[2], 2.0);
  ASSERT_EQ(s.clip.planes.size(), 1u);
  EXPECT_EQ(s.clip.planes[0].normal, Eigen::Vector3d::UnitX());
  // A camera alone still reads, with no settings.
  SavedViewSettings none;
  ParseView(R"({"width": 64, "height": 48})", "v", &none);
  EXPECT_TRUE(none.layer_names.empty());
  EXPECT_TRUE(none.clip.empty());
}

TEST(ViewJson, NamesWhatIsWrongInTheSettings) {
  auto message = [](const std::string& settings) {
    try {
      ParseView(R"({"width": 64, "height": 48, "settings": )" + settings + "}", "view.json");
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(R"({"layers": [1, 17], "layer_names": ["a", "b"]})").find("/settings/layers/1"), std::string::npos);
  EXPECT_NE(message(R"({"layers": [1], "layer_names": []})").find("1 shares for 0 layer_names"), std::string::npos);
  EXPECT_NE(message(R"({"clip": [[0, 0, 0, 1, 0]]})").find("/settings/clip/0"), std::string::npos);
  EXPECT_NE(message(R"({"clip": [[0, 0, 0, 0, 0, 0]]})").find("/settings/clip"), std::string::npos);
  EXPECT_NE(message(R"({"layers": [null], "layer_names": ["a"]})").find("settings/layers/0"), std::string::npos);
  EXPECT_NE(message(R"({"colour": 1})").find("unknown key"), std::string::npos);
  EXPECT_NE(message("[]").find("/settings"), std::string::npos);
}

}  // namespace
}  // namespace candi::render

#include "core/spbr_settings.h"

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "tests/util/option_check.h"

namespace candi {
namespace {

using testing::OptionCheckMessage;

TEST(SpbrSettings, DefaultsPassAndBadValuesNameTheField) {
  EXPECT_NO_THROW(SpbrSettings{}.Check());
  SpbrSettings s;
  s.repeat_level = 0;
  EXPECT_EQ(OptionCheckMessage(s), "SpbrSettings::repeat_level = 0; must be in [1, 100000]");
  s = {};
  s.repeat_level = kMaxRepeatLevel + 1;
  EXPECT_EQ(OptionCheckMessage(s), "SpbrSettings::repeat_level = 100001; must be in [1, 100000]");
  s = {};
  s.point_size = 0.5;
  EXPECT_EQ(OptionCheckMessage(s), "SpbrSettings::point_size = 0.5; must be in [1, 64]");
  s = {};
  s.point_size = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(s.Check(), std::invalid_argument);
  ImageSettings i;
  EXPECT_NO_THROW(i.Check());
  i.width = 0;
  EXPECT_EQ(OptionCheckMessage(i), "ImageSettings::width = 0; must be in [1, 16384]");
}

// Opaque draws every point once: one ensemble, whatever L says.
TEST(SpbrSettings, OpaqueMeansOneEnsemble) {
  SpbrSettings s;
  s.repeat_level = 64;
  EXPECT_EQ(s.EffectiveRepeatLevel(), 64);
  s.opaque = true;
  EXPECT_EQ(s.EffectiveRepeatLevel(), 1);
  EXPECT_NE(s, SpbrSettings{});
}

TEST(Brightness, OneParserOneRange) {
  EXPECT_TRUE(Brightness::Parse("auto").automatic());
  EXPECT_TRUE(Brightness::Parse("none").none());
  EXPECT_EQ(Brightness::Parse("none").gain(), 1.0);
  EXPECT_EQ(Brightness::Parse("2.5").gain(), 2.5);
  EXPECT_EQ(Brightness::Parse("100").gain(), 100.0);
  EXPECT_EQ(Brightness::Parse("1e-3").gain(), 1e-3);
  EXPECT_EQ(Brightness::Auto().AsNumber(), -1.0);
  EXPECT_EQ(Brightness::None().AsNumber(), 1.0);
  for (const char* bad :
       {"", "0", "-1", "100.5", "1e309", "nan", "inf", "2,5", "2.5x", " 2", "AUTO", "1 "}) {
    try {
      Brightness::Parse(bad);
      ADD_FAILURE() << "'" << bad << "' was taken";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()),
                "'" + std::string(bad) + "': expected auto, none or a gain in (0, 100]");
    }
  }
  EXPECT_THROW(Brightness::Gain(0), std::invalid_argument);
  EXPECT_THROW(Brightness::Gain(std::numeric_limits<double>::quiet_NaN()), std::invalid_argument);
  EXPECT_NO_THROW(Brightness::Gain(Brightness::kMaxGain));
}

// Its text reads back to the same value (a record written and read again keeps it).
TEST(Brightness, TextRoundTrips) {
  for (const Brightness& b :
       {Brightness::Auto(), Brightness::None(), Brightness::Gain(1), Brightness::Gain(1.25),
        Brightness::Gain(0.1 + 0.2), Brightness::Gain(99.999999999)}) {
    EXPECT_EQ(Brightness::Parse(b.ToString()), b) << b.ToString();
  }
  EXPECT_EQ(Brightness::Gain(1.5).ToString(), "1.5");
  // A gain of 1 is not "none": the same image, but what was asked is kept.
  EXPECT_NE(Brightness::Gain(1), Brightness::None());
}

}  // namespace
}  // namespace candi

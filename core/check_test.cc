#include "core/check.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "tests/util/option_check.h"

namespace candi {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

using testing::OptionCheckMessage;

struct TileSize {
  int tile = 256;
};

enum class Mode { kA = 0, kB = 7 };

// One rule of each macro; every default passes.
struct DemoOptions {
  double spacing = 1;
  int count = 3;
  double ratio = 0.5;
  double limit = 2;
  float alpha = 0.5f;
  std::vector<double> shares;
  double radius = 0;
  std::string name = "a b";
  int pixels = 0;
  int size = 1;
  TileSize tiles;
  void Check() const {
    CANDI_CHECK_OPTION_GT(spacing, 0);
    CANDI_CHECK_OPTION_GE(count, 1);
    CANDI_CHECK_OPTION_LT(ratio, 1);
    CANDI_CHECK_OPTION_LE(limit, 1e3);
    CANDI_CHECK_OPTION_IN(alpha, 0, 1);
    CANDI_CHECK_OPTION_EACH_IN(shares, 0, 16);
    CANDI_CHECK_OPTION(radius >= 0 && std::isfinite(radius), radius,
                       "finite and >= 0 (0 = automatic)");
    CANDI_CHECK_OPTION_MSG(!name.empty(), name, "must name something");
    CANDI_CHECK_OPTION_PAIR((pixels > 0) != (size > 0), pixels, size, "exactly one must be > 0");
    CANDI_CHECK_OPTION(tiles.tile % 32 == 0, tiles.tile, "a multiple of 32");
  }
};

TEST(CandiCheckOption, DefaultsPass) { EXPECT_EQ(OptionCheckMessage(DemoOptions()), "no throw"); }

TEST(CandiCheckOption, EachMacroNamesTheStructTheFieldItsValueAndTheRule) {
  DemoOptions o;
  o.spacing = -1;
  EXPECT_EQ(OptionCheckMessage(o), "DemoOptions::spacing = -1; must be > 0");
  o = {};
  o.count = 0;
  EXPECT_EQ(OptionCheckMessage(o), "DemoOptions::count = 0; must be >= 1");
  o = {};
  o.ratio = 1;
  EXPECT_EQ(OptionCheckMessage(o), "DemoOptions::ratio = 1; must be < 1");
  o = {};
  o.limit = 1000.5;
  EXPECT_EQ(OptionCheckMessage(o),
            "DemoOptions::limit = 1000.5; must be <= 1e3");  // bounds as written
  o = {};
  o.alpha = 1.1f;
  EXPECT_EQ(OptionCheckMessage(o),
            "DemoOptions::alpha = 1.1; must be in [0, 1]");  // float: shortest
  o = {};
  o.shares = {1, 0, 17};
  EXPECT_EQ(OptionCheckMessage(o), "DemoOptions::shares[2] = 17; must be in [0, 16]");
  o = {};
  o.radius = std::numeric_limits<double>::infinity();
  EXPECT_EQ(OptionCheckMessage(o),
            "DemoOptions::radius = inf; must be finite and >= 0 (0 = automatic)");
  o = {};
  o.name = "";
  EXPECT_EQ(OptionCheckMessage(o), "DemoOptions::name = ; must name something");
  o = {};
  o.pixels = 640;
  EXPECT_EQ(OptionCheckMessage(o),
            "DemoOptions::pixels = 640 and size = 1; exactly one must be > 0");
}

TEST(CandiCheckOption, NestedFieldsReadAsWritten) {
  DemoOptions o;
  o.tiles.tile = 100;
  EXPECT_EQ(OptionCheckMessage(o), "DemoOptions::tiles.tile = 100; must be a multiple of 32");
}

TEST(CandiCheckOption, NaNFailsEveryComparison) {
  DemoOptions o;
  o.spacing = kNaN;
  EXPECT_EQ(OptionCheckMessage(o), "DemoOptions::spacing = nan; must be > 0");
  o = {};
  o.ratio = kNaN;
  EXPECT_EQ(OptionCheckMessage(o), "DemoOptions::ratio = nan; must be < 1");
  o = {};
  o.limit = kNaN;
  EXPECT_EQ(OptionCheckMessage(o), "DemoOptions::limit = nan; must be <= 1e3");
  o = {};
  o.alpha = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(OptionCheckMessage(o), "DemoOptions::alpha = nan; must be in [0, 1]");
  o = {};
  o.shares = {kNaN};
  EXPECT_EQ(OptionCheckMessage(o), "DemoOptions::shares[0] = nan; must be in [0, 16]");
  o = {};
  o.radius = kNaN;
  EXPECT_EQ(OptionCheckMessage(o),
            "DemoOptions::radius = nan; must be finite and >= 0 (0 = automatic)");
}

struct GeOptions {
  double minimum = 0;
  void Check() const { CANDI_CHECK_OPTION_GE(minimum, 0); }
};

TEST(CandiCheckOption, NaNFailsGreaterOrEqual) {
  GeOptions o;
  EXPECT_EQ(OptionCheckMessage(o), "no throw");
  o.minimum = kNaN;
  EXPECT_EQ(OptionCheckMessage(o), "GeOptions::minimum = nan; must be >= 0");
}

TEST(CandiCheckOption, ValuesPrintInFullOrShortestAndBoolsStringsEnumsSequencesAsThemselves) {
  using internal::OptionValueText;
  EXPECT_EQ(OptionValueText(std::numeric_limits<int64_t>::min()), "-9223372036854775808");
  EXPECT_EQ(OptionValueText(std::numeric_limits<uint64_t>::max()), "18446744073709551615");
  EXPECT_EQ(OptionValueText(0.5), "0.5");  // std::to_string gave "0.500000"
  EXPECT_EQ(OptionValueText(0.1), "0.1");
  EXPECT_EQ(OptionValueText(1e-20), "1e-20");
  EXPECT_EQ(OptionValueText(123456.789), "123456.789");
  EXPECT_EQ(OptionValueText(-std::numeric_limits<double>::infinity()), "-inf");
  EXPECT_EQ(OptionValueText(0.1f), "0.1");
  EXPECT_EQ(OptionValueText(true), "true");
  EXPECT_EQ(OptionValueText(false), "false");
  EXPECT_EQ(OptionValueText(std::string("panel x")), "panel x");
  EXPECT_EQ(OptionValueText("auto"), "auto");
  EXPECT_EQ(OptionValueText(Mode::kB), "7");
  EXPECT_EQ(OptionValueText(std::optional<double>()), "none");
  EXPECT_EQ(OptionValueText(std::optional<double>(2.5)), "2.5");
  EXPECT_EQ(OptionValueText(std::vector<int>{1, 2, 3}), "(1, 2, 3)");
  EXPECT_EQ(OptionValueText(Eigen::Vector3d(0.001, 0, kNaN)), "(0.001, 0, nan)");
  EXPECT_EQ(OptionValueText(std::vector<double>()), "()");
}

}  // namespace

namespace sampling::inner {
struct DeepOptions {
  int level = 0;
  void Check() const { CANDI_CHECK_OPTION_GE(level, 1); }
};
template <typename T>
struct Holder {};
}  // namespace sampling::inner

TEST(CandiCheckOption, StructNameIsCutFromItsNamespaces) {
  EXPECT_EQ(OptionCheckMessage(sampling::inner::DeepOptions()),
            "DeepOptions::level = 0; must be >= 1");
  EXPECT_EQ(internal::OptionsStructName(typeid(sampling::inner::DeepOptions)), "DeepOptions");
  EXPECT_EQ(
      internal::OptionsStructName(typeid(sampling::inner::Holder<sampling::inner::DeepOptions>)),
      "Holder<candi::sampling::inner::DeepOptions>");
  EXPECT_EQ(internal::OptionsStructName(typeid(int)), "int");
}

namespace {

TEST(CandiCheck, PassesSilentlyAndThrowsWithFileLineAndMessage) {
  EXPECT_NO_THROW(CANDI_CHECK(1 + 1 == 2) << "never built");
  try {
    const int value = 3;
    CANDI_CHECK(value < 2) << "value = " << value;
    FAIL() << "no throw";
  } catch (const InternalError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("check_test.cc:"), std::string::npos) << what;
    EXPECT_NE(what.find("check failed: value < 2: value = 3"), std::string::npos) << what;
  }
}

TEST(CandiCheck, ComparisonMacrosPrintBothSides) {
  try {
    CANDI_CHECK_EQ(2, 3);
    FAIL();
  } catch (const InternalError& e) {
    EXPECT_NE(std::string(e.what()).find("2 = 2, 3 = 3"), std::string::npos) << e.what();
  }
}

TEST(InputError, NamesPathAndPosition) {
  const InputError e("a/b.ply", "line 7", "bad token");
  EXPECT_STREQ(e.what(), "a/b.ply: line 7: bad token");
  EXPECT_EQ(e.path(), "a/b.ply");
  EXPECT_STREQ(InputError("x.las", "", "empty").what(), "x.las: empty");
}

}  // namespace
}  // namespace candi

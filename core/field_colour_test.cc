#include "core/field_colour.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <set>

#include "core/check.h"

namespace candi {
namespace {

const double kNoValue = std::numeric_limits<double>::quiet_NaN();

PointCloud CloudWithField(const std::vector<double>& values, const std::string& name = "distance") {
  PointCloud cloud;
  cloud.frame.origin = Eigen::Vector3d(416000, 9168000, 200);
  cloud.Resize(values.size());
  const int k = cloud.AddScalarField(name, ScalarType::kFloat64);
  for (size_t i = 0; i < values.size(); ++i) {
    cloud.positions[i] = Eigen::Vector3d(i * 0.01, 0, 0.001 * i);
    cloud.scalars[k].Set(i, values[i]);
  }
  return cloud;
}

TEST(FieldColour, AutoDivergingRangeIsSymmetricAndCountsOutsideAndUndefined) {
  std::vector<double> v;
  for (int i = -500; i <= 500; ++i) v.push_back(i * 1e-5);  // +-5 mm
  v.push_back(0.5);                                         // one far outlier
  v.push_back(kNoValue);
  const PointCloud cloud = CloudWithField(v);
  const std::vector<double> values = FieldValues(cloud, "distance", "a.ply");
  FieldColouring c;
  c.field = "distance";
  const FieldLegend legend = ResolveFieldColouring(c, {&values});
  EXPECT_EQ(legend.scale, FieldScale::kDiverging);
  EXPECT_DOUBLE_EQ(legend.lo, -legend.hi);
  EXPECT_NEAR(legend.hi, 0.0049, 0.0002);  // the 98th percentile of |v|, not the outlier
  EXPECT_EQ(legend.count, v.size());
  EXPECT_EQ(legend.undefined, 1u);
  EXPECT_GE(legend.outside, 1u);
  EXPECT_LE(legend.outside, 25u);
  EXPECT_TRUE(legend.Colour(0.5) == kOutOfRangeGrey);
  EXPECT_TRUE(legend.Colour(kNoValue) == kOutOfRangeGrey);
  EXPECT_TRUE(legend.Colour(0.0) == DivergingColour(0.0));
  // Negative is blue, positive red.
  EXPECT_GT(legend.Colour(-0.004).b, legend.Colour(-0.004).r);
  EXPECT_GT(legend.Colour(0.004).r, legend.Colour(0.004).b);
}

TEST(FieldColour, GivenRangeAndScaleAreKept) {
  const PointCloud cloud = CloudWithField({1, 2, 3, 4, 5}, "intensity");
  const std::vector<double> values = FieldValues(cloud, "intensity", "a.las");
  FieldColouring c;
  c.field = "intensity";
  c.lo = 2;
  c.hi = 4;
  const FieldLegend legend = ResolveFieldColouring(c, {&values});
  EXPECT_EQ(legend.scale, FieldScale::kSequential);  // one sign: sequential
  EXPECT_EQ(legend.lo, 2);
  EXPECT_EQ(legend.hi, 4);
  EXPECT_EQ(legend.outside, 2u);
  EXPECT_TRUE(legend.Colour(2) == SequentialColour(0));
  EXPECT_TRUE(legend.Colour(4) == SequentialColour(1));
}

TEST(FieldColour, ElevationIsWorldZAtSurveyCoordinates) {
  const PointCloud cloud = CloudWithField({0, 0, 0});
  const std::vector<double> z = FieldValues(cloud, "elevation", "a.ply");
  ASSERT_EQ(z.size(), 3u);
  EXPECT_DOUBLE_EQ(z[0], 200.0);
  EXPECT_NEAR(z[2], 200.002, 1e-12);
  FieldColouring c;
  c.field = "elevation";
  const FieldLegend legend = ResolveFieldColouring(c, {&z});
  EXPECT_EQ(legend.scale, FieldScale::kSequential);
  EXPECT_LT(legend.lo, legend.hi);
  EXPECT_GE(legend.lo, 200.0);
  EXPECT_LE(legend.hi, 200.002);
}

TEST(FieldColour, ClassesArePaletteColoursWithThePresentClassesListed) {
  const PointCloud cloud = CloudWithField({2, 6, 6, 2, 9, 42}, "classification");
  const std::vector<double> v = FieldValues(cloud, "classification", "a.las");
  FieldColouring c;
  c.field = "classification";
  const FieldLegend legend = ResolveFieldColouring(c, {&v});
  EXPECT_EQ(legend.scale, FieldScale::kClasses);
  EXPECT_EQ(legend.classes, (std::vector<int>{2, 6, 9, 42}));
  EXPECT_TRUE(legend.Colour(2) == ClassColour(2));
  EXPECT_FALSE(ClassColour(2) == ClassColour(6));
  EXPECT_EQ(ClassName(6), "building");
  EXPECT_EQ(ClassName(42), "class 42");
  EXPECT_EQ(legend.outside, 0u);
}

TEST(FieldColour, ColourByFieldAddsColoursToACloudWithout) {
  PointCloud cloud = CloudWithField({-1, 0, 1, kNoValue});
  ASSERT_FALSE(cloud.schema.colors);
  const std::vector<double> v = FieldValues(cloud, "distance", "a.ply");
  FieldColouring c;
  c.field = "distance";
  c.lo = -1;
  c.hi = 1;
  const FieldLegend legend = ResolveFieldColouring(c, {&v});
  ColourByField(legend, v, &cloud);
  ASSERT_TRUE(cloud.schema.colors);
  cloud.CheckConsistent();
  EXPECT_TRUE(cloud.colors[0] == DivergingColour(-1));
  EXPECT_TRUE(cloud.colors[2] == DivergingColour(1));
  EXPECT_TRUE(cloud.colors[3] == kOutOfRangeGrey);
}

TEST(FieldColour, DegenerateValuesGiveAUsableRange) {
  for (const std::vector<double>& v : {std::vector<double>{}, std::vector<double>{kNoValue, kNoValue},
                                       std::vector<double>{0, 0, 0}, std::vector<double>{7, 7}}) {
    FieldColouring c;
    c.field = "f";
    const FieldLegend legend = ResolveFieldColouring(c, {&v});
    EXPECT_TRUE(std::isfinite(legend.lo) && std::isfinite(legend.hi));
    EXPECT_LT(legend.lo, legend.hi);
    for (double x : v) {
      if (std::isfinite(x)) {
        EXPECT_FALSE(legend.Colour(x) == kOutOfRangeGrey) << x;
      }
    }
  }
}

TEST(FieldColour, BadInputIsNamed) {
  const PointCloud cloud = CloudWithField({1, 2}, "distance");
  try {
    FieldValues(cloud, "lod95", "scan.ply");
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("scan.ply"), std::string::npos) << what;
    EXPECT_NE(what.find("lod95"), std::string::npos) << what;
    EXPECT_NE(what.find("distance"), std::string::npos) << what;  // what it has
  }
  FieldColouring c;
  c.field = "distance";
  c.lo = 1;
  EXPECT_THROW(c.Check(), std::invalid_argument);  // one end only
  c.hi = 1;
  EXPECT_THROW(c.Check(), std::invalid_argument);  // empty range
  c.hi = std::numeric_limits<double>::infinity();
  EXPECT_THROW(c.Check(), std::invalid_argument);
  EXPECT_THROW(ParseFieldScale("rainbow"), std::invalid_argument);
}

TEST(FieldColour, AColourReadsBackAsItsValue) {
  FieldLegend l;
  l.field = "distance";
  l.scale = FieldScale::kDiverging;
  l.lo = -0.01;
  l.hi = 0.01;
  for (double v : {-0.0099, -0.004, -0.0003, 0.0, 0.0021, 0.0087}) {
    double half = 0;
    const std::optional<double> back = l.ValueOfColour(l.Colour(v), &half);
    ASSERT_TRUE(back.has_value()) << v;
    EXPECT_LE(std::abs(*back - v), half + 1e-12) << v;
    EXPECT_LT(half, 0.0002) << v;  // 8-bit colours: about a hundredth of the range at worst
  }
  // Values over the whole scale, and every value whose colour the scale's samples skip (where two
  // channels change within one sample step, the colour between the changes shows at neither
  // end): each reads back within its half-width.
  std::vector<double> probes;
  for (int i = 0; i <= 2000; ++i) probes.push_back(l.lo + (l.hi - l.lo) * i / 2000.0);
  const double step = (l.hi - l.lo) / FieldLegend::kColourSteps;
  size_t skipped = 0;
  for (int i = 0; i < FieldLegend::kColourSteps; ++i) {
    const Rgb8 a = l.Colour(l.lo + step * i), b = l.Colour(l.lo + step * (i + 1));
    for (int j = 1; j < 16; ++j) {
      const double v = l.lo + step * (i + j / 16.0);
      const Rgb8 c = l.Colour(v);
      if (!(c == a) && !(c == b)) probes.push_back(v), ++skipped;
    }
  }
  std::printf("%zu of %d sub-step values show a colour the samples skip\n", skipped, 15 * FieldLegend::kColourSteps);
  size_t worst = 0;
  double worst_error = 0;
  for (size_t i = 0; i < probes.size(); ++i) {
    const double v = probes[i];
    double half = 0;
    const std::optional<double> back = l.ValueOfColour(l.Colour(v), &half);
    ASSERT_TRUE(back.has_value()) << v;
    ASSERT_LE(std::abs(*back - v), half + 1e-12) << v;
    if (std::abs(*back - v) > worst_error) worst_error = std::abs(*back - v), worst = i;
  }
  EXPECT_LT(worst_error, 0.0002) << "at probe " << worst;
  double half = 0;
  EXPECT_FALSE(l.ValueOfColour(kOutOfRangeGrey, &half).has_value());
  EXPECT_FALSE(l.ValueOfColour({0, 255, 0}, &half).has_value());  // not on the scale
  FieldLegend classes;
  classes.scale = FieldScale::kClasses;
  classes.classes = {2, 6};
  EXPECT_EQ(classes.ValueOfColour(ClassColour(6), &half), 6.0);
  EXPECT_FALSE(classes.ValueOfColour(ClassColour(9), &half).has_value());  // not present
}

// The runs a page decodes picks from: they tile the samples in order, each a different colour
// from the one before, and the colours come back in the order of the values (the scale is
// monotonic between its stops, so no colour runs twice).
TEST(FieldColour, ColourRunsTileTheScaleOnce) {
  for (FieldScale scale : {FieldScale::kDiverging, FieldScale::kSequential}) {
    FieldLegend l;
    l.scale = scale;
    l.lo = -2;
    l.hi = 3;
    const std::vector<FieldLegend::ColourRun> runs = l.ColourRuns();
    ASSERT_GT(runs.size(), 100u) << FieldScaleName(scale);  // 8-bit colours: hundreds along a scale
    EXPECT_EQ(runs.front().first, 0);
    EXPECT_EQ(runs.back().last, FieldLegend::kColourSteps);
    std::set<uint32_t> seen;
    for (size_t k = 0; k < runs.size(); ++k) {
      if (k > 0) {
        EXPECT_EQ(runs[k].first, runs[k - 1].last + 1);
      }
      EXPECT_LE(runs[k].first, runs[k].last);
      const Rgb8 c = runs[k].colour;
      EXPECT_TRUE(seen.insert((c.r << 16) | (c.g << 8) | c.b).second) << "colour of run " << k << " runs twice";
    }
  }
  FieldLegend classes;
  classes.scale = FieldScale::kClasses;
  EXPECT_TRUE(classes.ColourRuns().empty());
}

// An elevation crossing zero (a site near sea level) is a level, not a deviation: sequential.
TEST(FieldColour, ElevationCrossingZeroIsSequential) {
  PointCloud cloud = CloudWithField({-1, 0, 2}, "height");
  cloud.frame.origin.z() = -0.001;  // z: -1, 0, +1 mm
  const std::vector<double> z = FieldValues(cloud, "elevation", "cloud");
  ASSERT_LT(z.front(), 0);
  ASSERT_GT(z.back(), 0);
  FieldColouring c;
  c.field = "elevation";
  EXPECT_EQ(ResolveFieldColouring(c, {&z}).scale, FieldScale::kSequential);
  c.field = "height";  // any other signed field: diverging
  const std::vector<double> h = FieldValues(cloud, "height", "cloud");
  EXPECT_EQ(ResolveFieldColouring(c, {&h}).scale, FieldScale::kDiverging);
}

}  // namespace
}  // namespace candi

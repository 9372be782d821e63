#include "render/legend.h"

#include <gtest/gtest.h>

namespace candi::render {
namespace {

int CountColour(const Image8& image, Rgb8 c) {
  int n = 0;
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      n += image.at(x, y, 0) == c.r && image.at(x, y, 1) == c.g && image.at(x, y, 2) == c.b;
    }
  }
  return n;
}

FieldLegend Deviation() {
  FieldLegend l;
  l.field = "distance";
  l.scale = FieldScale::kDiverging;
  l.lo = -0.01;
  l.hi = 0.01;
  l.count = 100;
  l.outside = 3;
  l.undefined = 2;
  return l;
}

TEST(Legend, NumbersHaveThreeSignificantDigits) {
  EXPECT_EQ(LegendNumber(0), "0");
  EXPECT_EQ(LegendNumber(-0.0125), "-0.0125");
  EXPECT_EQ(LegendNumber(0.01), "0.01");
  EXPECT_EQ(LegendNumber(1234567), "1.23e+06");
}

TEST(Legend, TextDrawsItsGlyphs) {
  Image8 image(60, 10, 3);
  const int w = DrawText("1-", 0, 0, 1, {255, 255, 255}, &image);
  EXPECT_EQ(w, 11);
  // '1' has 5 + 1 + 1 + 1 + 1 + 3 = 12 pixels... counted from its rows: 1, 2, 1, 1, 1, 1, 3.
  // '-' has 5.
  EXPECT_EQ(CountColour(image, {255, 255, 255}), 10 + 5);
  Image8 lower(60, 10, 3), upper(60, 10, 3);
  DrawText("dist", 0, 0, 1, {255, 255, 255}, &lower);
  DrawText("DIST", 0, 0, 1, {255, 255, 255}, &upper);
  EXPECT_TRUE(lower == upper);
}

TEST(Legend, DivergingBarSpansTheScaleWithGreyAndText) {
  Image8 image(640, 480, 3, 40);
  const FieldLegend l = Deviation();
  ASSERT_TRUE(DrawFieldLegend(l, &image));
  // The bar runs from the scale's deep blue through its white to its deep red; the grey swatch
  // is there; white text.
  int blue = 0, red = 0;
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      blue += image.at(x, y, 2) > image.at(x, y, 0) + 80;
      red += image.at(x, y, 0) > image.at(x, y, 2) + 80;
    }
  }
  EXPECT_GT(blue, 100);
  EXPECT_GT(red, 100);
  int pale = 0;  // the scale's white middle (not the text's pure white)
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      pale += image.at(x, y, 0) > 235 && image.at(x, y, 0) < 255 && image.at(x, y, 2) > 235 && image.at(x, y, 2) < 255;
    }
  }
  EXPECT_GT(pale, 10);
  EXPECT_GT(CountColour(image, kOutOfRangeGrey), 40);
  EXPECT_GT(CountColour(image, {255, 255, 255}), 200);
  // Drawn at the bottom left: the top right quarter is untouched.
  for (int y = 0; y < 240; ++y) {
    for (int x = 320; x < 640; ++x) ASSERT_EQ(image.at(x, y, 0), 40);
  }
  // The same legend twice: the same pixels.
  Image8 again(640, 480, 3, 40);
  DrawFieldLegend(l, &again);
  EXPECT_TRUE(image == again);
}

TEST(Legend, ClassesListTheirColours) {
  Image8 image(800, 600, 3);
  FieldLegend l;
  l.field = "classification";
  l.scale = FieldScale::kClasses;
  l.classes = {2, 6, 9};
  ASSERT_TRUE(DrawFieldLegend(l, &image));
  for (int c : l.classes) EXPECT_GT(CountColour(image, ClassColour(c)), 20) << c;
  EXPECT_EQ(CountColour(image, kOutOfRangeGrey), 0);  // no undefined values: no grey line
}

TEST(Legend, TooSmallAnImageIsLeftAlone) {
  Image8 image(60, 40, 3, 7);
  const Image8 before = image;
  EXPECT_FALSE(DrawFieldLegend(Deviation(), &image));
  EXPECT_TRUE(image == before);
}

}  // namespace
}  // namespace candi::render

#include "section/section_lines.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <vector>

#include "core/rng.h"

namespace candi::section {
namespace {

constexpr double kPi = 3.14159265358979323846;
using Curve = std::function<Eigen::Vector2d(double)>;  // parameter in [0, 1]

// Points at `per_metre` uniformly random positions along the curve's arc length (Poisson), plus
// Gaussian noise of `noise` m on each coordinate.
std::vector<Eigen::Vector2d> SampleCurve(const Curve& curve, double per_metre, double noise,
                                         Rng* rng) {
  constexpr int kSteps = 100000;
  std::vector<double> arc(kSteps + 1, 0.0);  // arc length at parameter k / kSteps
  for (int k = 1; k <= kSteps; ++k) {
    arc[k] = arc[k - 1] + (curve(double(k) / kSteps) - curve(double(k - 1) / kSteps)).norm();
  }
  const size_t n = static_cast<size_t>(std::lround(per_metre * arc.back()));
  std::vector<Eigen::Vector2d> points;
  for (size_t i = 0; i < n; ++i) {
    const double s = rng->Uniform(0, arc.back());
    const size_t k =
        std::min<size_t>(std::upper_bound(arc.begin(), arc.end(), s) - arc.begin(), kSteps);
    const double f = (s - arc[k - 1]) / std::max(arc[k] - arc[k - 1], 1e-300);
    const Eigen::Vector2d p = curve((double(k - 1) + f) / kSteps);
    points.push_back(p + noise * Eigen::Vector2d(rng->Normal(), rng->Normal()));
  }
  return points;
}

Curve Segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return [a, b](double t) { return (a + t * (b - a)).eval(); };
}

void Append(std::vector<Eigen::Vector2d>* to, const std::vector<Eigen::Vector2d>& from) {
  to->insert(to->end(), from.begin(), from.end());
}

// The outline of an axis-aligned rectangle, sampled side by side.
std::vector<Eigen::Vector2d> Rectangle(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
                                       double per_metre, double noise, Rng* rng) {
  const Eigen::Vector2d c[4] = {lo, {hi.x(), lo.y()}, hi, {lo.x(), hi.y()}};
  std::vector<Eigen::Vector2d> points;
  for (int k = 0; k < 4; ++k) {
    Append(&points, SampleCurve(Segment(c[k], c[(k + 1) % 4]), per_metre, noise, rng));
  }
  return points;
}

double DistanceToRectangle(const Eigen::Vector2d& p, const Eigen::Vector2d& lo,
                           const Eigen::Vector2d& hi) {
  const Eigen::Vector2d q = p.cwiseMax(lo).cwiseMin(hi);
  if (q != p) return (p - q).norm();  // outside
  return std::min({p.x() - lo.x(), hi.x() - p.x(), p.y() - lo.y(), hi.y() - p.y()});
}

// The hill v = 3 sin(2 pi u / 40), u in [0, 160]: least radius of curvature 40^2 / (4 pi^2 3) =
// 13.5 m.
constexpr double kHillAmplitude = 3.0, kHillPeriod = 40.0, kHillLength = 160.0;
double Hill(double u) { return kHillAmplitude * std::sin(2 * kPi * u / kHillPeriod); }

// Distance from p to the hill: the closest u by a scan of +-1 m, then golden-section search.
double DistanceToHill(const Eigen::Vector2d& p) {
  auto d2 = [&](double u) { return (Eigen::Vector2d(u, Hill(u)) - p).squaredNorm(); };
  double best = p.x();
  for (double u = p.x() - 1; u <= p.x() + 1; u += 0.01) {
    if (d2(u) < d2(best)) best = u;
  }
  double a = best - 0.01, b = best + 0.01;
  const double g = (std::sqrt(5.0) - 1) / 2;
  for (int i = 0; i < 60; ++i) {
    const double c = b - g * (b - a), d = a + g * (b - a);
    if (d2(c) < d2(d)) {
      b = d;  // the minimum lies in [a, d]
    } else {
      a = c;
    }
  }
  return std::sqrt(d2(0.5 * (a + b)));
}

struct Deviation {
  double mean = 0, max = 0;
};

// Deviation of the vertices (or, with chords, of the segment midpoints) from a curve.
Deviation Measure(const Polyline2& line, const std::function<double(const Eigen::Vector2d&)>& dist,
                  bool chords = false) {
  Deviation dev;
  const size_t n = chords ? line.points.size() - (line.closed ? 0 : 1) : line.points.size();
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d p =
        chords ? 0.5 * (line.points[i] + line.points[(i + 1) % line.points.size()])
               : line.points[i];
    const double d = dist(p);
    dev.mean += d / static_cast<double>(n);
    dev.max = std::max(dev.max, d);
  }
  return dev;
}

double LineLength(const Polyline2& line) {
  double length = 0;
  for (size_t i = 1; i < line.points.size(); ++i) {
    length += (line.points[i] - line.points[i - 1]).norm();
  }
  if (line.closed) length += (line.points.front() - line.points.back()).norm();
  return length;
}

// The least distance from p to any vertex of any line.
double NearestVertex(const SectionLines& r, const Eigen::Vector2d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Polyline2& line : r.lines) {
    for (const Eigen::Vector2d& q : line.points) best = std::min(best, (q - p).norm());
  }
  return best;
}

double SignedArea(const Polyline2& line) {
  double area = 0;
  for (size_t i = 0; i < line.points.size(); ++i) {
    const Eigen::Vector2d& a = line.points[i];
    const Eigen::Vector2d& b = line.points[(i + 1) % line.points.size()];
    area += 0.5 * (a.x() * b.y() - a.y() * b.x());
  }
  return area;
}

std::vector<Eigen::Vector2d> HillPoints(uint64_t seed) {
  Rng rng(seed);
  return SampleCurve(
      [](double t) { return Eigen::Vector2d(kHillLength * t, Hill(kHillLength * t)); }, 5.0, 0.001,
      &rng);
}

void ExpectSameBytes(const SectionLines& a, const SectionLines& b) {
  ASSERT_EQ(a.lines.size(), b.lines.size());
  EXPECT_EQ(a.spacing, b.spacing);
  EXPECT_EQ(a.max_gap, b.max_gap);
  for (size_t k = 0; k < a.lines.size(); ++k) {
    EXPECT_EQ(a.lines[k].closed, b.lines[k].closed);
    ASSERT_EQ(a.lines[k].points.size(), b.lines[k].points.size());
    for (size_t i = 0; i < a.lines[k].points.size(); ++i) {
      EXPECT_EQ(a.lines[k].points[i].x(), b.lines[k].points[i].x());
      EXPECT_EQ(a.lines[k].points[i].y(), b.lines[k].points[i].y());
    }
  }
}

TEST(ExtractSectionLines, OptionsCheckDefaultsAndNameBadFields) {
  EXPECT_NO_THROW(SectionLineOptions().Check());
  SectionLineOptions o;
  o.spacing = -1;
  try {
    o.Check();
    ADD_FAILURE() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(),
                 "SectionLineOptions::spacing = -1; must be finite and >= 0 (0 = automatic)");
  }
  o = {};
  o.max_gap = -0.5;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.min_length = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.min_spacing = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.spacing = std::numeric_limits<double>::infinity();
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o.spacing = -1;  // ExtractSectionLines checks too, even on empty input
  EXPECT_THROW(ExtractSectionLines(o, {}), std::invalid_argument);
}

TEST(ExtractSectionLines, HillProfileIsAccurate) {
  const std::vector<Eigen::Vector2d> points = HillPoints(7);
  const SectionLines r = ExtractSectionLines({}, points);
  EXPECT_EQ(r.points, points.size());
  EXPECT_GT(r.spacing, 0.3);  // 2.5 point gaps of 0.2 m
  EXPECT_LT(r.spacing, 0.8);
  EXPECT_DOUBLE_EQ(r.max_gap, 6 * r.spacing);
  ASSERT_EQ(r.lines.size(), 1u);
  const Polyline2& line = r.lines[0];
  EXPECT_FALSE(line.closed);
  double first = kHillLength, last = 0;  // the data's extent
  for (const Eigen::Vector2d& p : points) {
    first = std::min(first, p.x());
    last = std::max(last, p.x());
  }
  EXPECT_NEAR(line.points.front().x(), first, 0.25 * r.spacing);  // end to end, u increasing
  EXPECT_NEAR(line.points.back().x(), last, 0.25 * r.spacing);
  const Deviation vertices = Measure(line, DistanceToHill);
  const Deviation chords = Measure(line, DistanceToHill, true);
  RecordProperty("vertex_mean_mm", std::to_string(vertices.mean * 1e3));
  RecordProperty("vertex_max_mm", std::to_string(vertices.max * 1e3));
  std::printf(
      "hill: %zu vertices, spacing %.3f m; vertices mean %.2f mm max %.2f mm; chords "
      "max %.2f mm\n",
      line.points.size(), r.spacing, vertices.mean * 1e3, vertices.max * 1e3, chords.max * 1e3);
  EXPECT_LE(vertices.mean, 0.002);
  EXPECT_LE(vertices.max, 0.01);
  EXPECT_LE(chords.max, 0.005);
  for (size_t i = 1; i < line.points.size(); ++i) {  // in curve order, evenly spaced
    const double step = (line.points[i] - line.points[i - 1]).norm();
    EXPECT_GT(line.points[i].x(), line.points[i - 1].x());
    EXPECT_LT(step, 1.6 * r.spacing);
  }
}

// A circle of radius `radius` around the origin, arc of `degrees`, 5 points/m, 1 mm noise.
void ExpectAccurateArc(double radius, double degrees, double max_chord) {
  Rng rng(11);
  const double span = degrees * kPi / 180;
  const std::vector<Eigen::Vector2d> points = SampleCurve(
      [&](double t) {
        return Eigen::Vector2d(radius * std::cos(span * t), radius * std::sin(span * t));
      },
      5.0, 0.001, &rng);
  const SectionLines r = ExtractSectionLines({}, points);
  ASSERT_EQ(r.lines.size(), 1u);
  auto dist = [&](const Eigen::Vector2d& p) { return std::abs(p.norm() - radius); };
  const Deviation vertices = Measure(r.lines[0], dist), chords = Measure(r.lines[0], dist, true);
  std::printf(
      "arc R %.0f m: %zu vertices, spacing %.3f m; vertices mean %.2f mm max %.2f mm; "
      "chords max %.2f mm\n",
      radius, r.lines[0].points.size(), r.spacing, vertices.mean * 1e3, vertices.max * 1e3,
      chords.max * 1e3);
  EXPECT_LE(vertices.mean, 0.002);
  EXPECT_LE(vertices.max, 0.01);
  EXPECT_LE(chords.max, max_chord);
  EXPECT_NEAR(LineLength(r.lines[0]), radius * span, 0.5);
}

TEST(ExtractSectionLines, CircleArcsAreAccurate) {
  ExpectAccurateArc(10.0, 300.0, 0.01);  // chords: s^2 / (8 R) = 3 mm at s = 0.5 m
  ExpectAccurateArc(20.0, 150.0, 0.005);
}

TEST(ExtractSectionLines, RectangleLoopIsClosed) {
  Rng rng(3);
  const Eigen::Vector2d lo(2, 1), hi(22, 9);
  const SectionLines r = ExtractSectionLines({}, Rectangle(lo, hi, 5.0, 0.001, &rng));
  ASSERT_EQ(r.lines.size(), 1u);
  const Polyline2& line = r.lines[0];
  EXPECT_TRUE(line.closed);
  EXPECT_NEAR(LineLength(line), 56.0, 1.0);       // the corners are cut by at most a spacing
  EXPECT_GT(SignedArea(line), 0);                 // counter-clockwise
  for (const Eigen::Vector2d& p : line.points) {  // from its least (u, v)
    EXPECT_TRUE(line.points[0].x() < p.x() ||
                (line.points[0].x() == p.x() && line.points[0].y() <= p.y()));
  }
  const Deviation dev =
      Measure(line, [&](const Eigen::Vector2d& p) { return DistanceToRectangle(p, lo, hi); });
  std::printf("rectangle: %zu vertices; mean %.2f mm max %.2f mm\n", line.points.size(),
              dev.mean * 1e3, dev.max * 1e3);
  EXPECT_LE(dev.mean, 0.01);
  EXPECT_LE(dev.max, 0.5 * r.spacing);
}

TEST(ExtractSectionLines, WallFacesGiveTwoLoops) {
  // A horizontal cut through the walls of a room: inner and outer faces 1 m (2 spacings) apart.
  Rng rng(5);
  const Eigen::Vector2d lo(0, 0), hi(10, 6), outer_lo(-1, -1), outer_hi(11, 7);
  std::vector<Eigen::Vector2d> points = Rectangle(lo, hi, 5.0, 0.001, &rng);
  Append(&points, Rectangle(outer_lo, outer_hi, 5.0, 0.001, &rng));
  const SectionLines r = ExtractSectionLines({}, points);
  ASSERT_EQ(r.lines.size(), 2u);
  EXPECT_TRUE(r.lines[0].closed);
  EXPECT_TRUE(r.lines[1].closed);
  EXPECT_NEAR(LineLength(r.lines[0]), 2 * (12 + 8), 1.0);  // the outer loop is longer
  EXPECT_NEAR(LineLength(r.lines[1]), 2 * (10 + 6), 1.0);
  const Deviation outer = Measure(r.lines[0], [&](const Eigen::Vector2d& p) {
    return DistanceToRectangle(p, outer_lo, outer_hi);
  });
  const Deviation inner =
      Measure(r.lines[1], [&](const Eigen::Vector2d& p) { return DistanceToRectangle(p, lo, hi); });
  std::printf("walls: outer mean %.2f mm max %.2f mm; inner mean %.2f mm max %.2f mm\n",
              outer.mean * 1e3, outer.max * 1e3, inner.mean * 1e3, inner.max * 1e3);
  EXPECT_LE(outer.mean, 0.005);
  EXPECT_LE(inner.mean, 0.005);
  EXPECT_LE(outer.max, 0.5 * r.spacing);  // at a corner; never across the wall
  EXPECT_LE(inner.max, 0.5 * r.spacing);
}

TEST(ExtractSectionLines, GapSplitsLine) {
  Rng rng(9);
  std::vector<Eigen::Vector2d> points =
      SampleCurve([](double t) { return Eigen::Vector2d(48 * t, Hill(48 * t)); }, 5, 0.001, &rng);
  Append(&points,
         SampleCurve([](double t) { return Eigen::Vector2d(53 + 47 * t, Hill(53 + 47 * t)); }, 5,
                     0.001, &rng));
  const SectionLines r = ExtractSectionLines({}, points);
  ASSERT_LT(r.max_gap, 5.0);
  ASSERT_EQ(r.lines.size(), 2u);
  const Polyline2& left = r.lines[0];  // 48 m, the longer
  const Polyline2& right = r.lines[1];
  EXPECT_LT(left.points.front().x(), 0.5);
  EXPECT_NEAR(left.points.back().x(), 48.0, 0.5);
  EXPECT_NEAR(right.points.front().x(), 53.0, 0.5);
  EXPECT_GT(right.points.back().x(), 99.5);
  EXPECT_LE(Measure(left, DistanceToHill).max, 0.01);
  EXPECT_LE(Measure(right, DistanceToHill).max, 0.01);
  // The same data with a max_gap above 5 m bridges the gap.
  SectionLineOptions o;
  o.max_gap = 6.0;
  const SectionLines bridged = ExtractSectionLines(o, points);
  ASSERT_EQ(bridged.lines.size(), 1u);
  EXPECT_LT(bridged.lines[0].points.front().x(), 0.5);
  EXPECT_GT(bridged.lines[0].points.back().x(), 99.5);
  EXPECT_NEAR(LineLength(bridged.lines[0]), LineLength(left) + LineLength(right) + 5.0, 1.0);
}

TEST(ExtractSectionLines, SeparateCurvesGiveSeparateLines) {
  Rng rng(13);
  std::vector<Eigen::Vector2d> points =
      SampleCurve(Segment({0, 0}, {30, 2}), 5, 0.001, &rng);  // a floor
  Append(&points, SampleCurve(
                      [](double t) {  // a vault above it
                        return Eigen::Vector2d(15 + 8 * std::cos(kPi * t),
                                               10 + 8 * std::sin(kPi * t));
                      },
                      5, 0.001, &rng));
  const SectionLines r = ExtractSectionLines({}, points);
  ASSERT_EQ(r.lines.size(), 2u);
  EXPECT_NEAR(LineLength(r.lines[0]), std::hypot(30.0, 2.0), 0.5);
  EXPECT_NEAR(LineLength(r.lines[1]), 8 * kPi, 0.5);
  EXPECT_FALSE(r.lines[0].closed);
  EXPECT_FALSE(r.lines[1].closed);
  EXPECT_LT(r.lines[1].points.front().x(), r.lines[1].points.back().x());
}

TEST(ExtractSectionLines, TJunctionCoversAllArms) {
  Rng rng(17);
  std::vector<Eigen::Vector2d> points = SampleCurve(Segment({-20, 0}, {20, 0}), 5, 0.001, &rng);
  Append(&points, SampleCurve(Segment({0, 0}, {0, -15}), 5, 0.001, &rng));
  const SectionLines r = ExtractSectionLines({}, points);
  ASSERT_GE(r.lines.size(), 2u);
  double total = 0;
  for (const Polyline2& line : r.lines) total += LineLength(line);
  EXPECT_NEAR(total, 55.0, 1.5);
  for (double s : {-19.5, -10.0, -2.0, 2.0, 10.0, 19.5}) {  // along the bar
    EXPECT_LT(NearestVertex(r, {s, 0}), 0.6) << s;
  }
  for (double s : {-2.0, -8.0, -14.5}) EXPECT_LT(NearestVertex(r, {0, s}), 0.6) << s;  // stem
  for (const Polyline2& line : r.lines) {
    for (const Eigen::Vector2d& p : line.points) {
      EXPECT_LT(std::min(std::abs(p.y()), std::abs(p.x())), 0.05) << p.transpose();
    }
  }
}

TEST(ExtractSectionLines, DegenerateInputGivesEmptyResult) {
  EXPECT_TRUE(ExtractSectionLines({}, {}).lines.empty());
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  SectionLines r = ExtractSectionLines({}, {{nan, 0}, {0, inf}, {nan, nan}});
  EXPECT_TRUE(r.lines.empty());
  EXPECT_EQ(r.points, 0u);
  r = ExtractSectionLines({}, std::vector<Eigen::Vector2d>(100, Eigen::Vector2d(3, 4)));
  EXPECT_TRUE(r.lines.empty());
  EXPECT_EQ(r.points, 100u);
  r = ExtractSectionLines({}, {{3, 4}, {nan, 1}});
  EXPECT_TRUE(r.lines.empty());
  EXPECT_EQ(r.points, 1u);
  r = ExtractSectionLines({}, {{0, 0}, {1, 0}});  // two points make no curve
  EXPECT_TRUE(r.lines.empty());
}

TEST(ExtractSectionLines, NonFinitePointsAreSkipped) {
  const std::vector<Eigen::Vector2d> clean = HillPoints(21);
  std::vector<Eigen::Vector2d> dirty = clean;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  dirty.insert(dirty.begin() + 100, Eigen::Vector2d(nan, 1.0));
  dirty.push_back(Eigen::Vector2d(2.0, -std::numeric_limits<double>::infinity()));
  const SectionLines a = ExtractSectionLines({}, clean), b = ExtractSectionLines({}, dirty);
  EXPECT_EQ(b.points, clean.size());
  ExpectSameBytes(a, b);
}

TEST(ExtractSectionLines, CollinearPointsWithoutNoise) {
  std::vector<Eigen::Vector2d> points;
  for (int i = 0; i <= 100; ++i) points.emplace_back(100.0 - 0.2 * i, 5.0);  // reversed order
  const SectionLines r = ExtractSectionLines({}, points);
  ASSERT_EQ(r.lines.size(), 1u);
  EXPECT_NEAR((r.lines[0].points.front() - Eigen::Vector2d(80.0, 5.0)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((r.lines[0].points.back() - Eigen::Vector2d(100.0, 5.0)).norm(), 0.0, 1e-9);
  for (const Eigen::Vector2d& p : r.lines[0].points) EXPECT_NEAR(p.y(), 5.0, 1e-9);
}

TEST(ExtractSectionLines, GivenSpacingIsUsed) {
  SectionLineOptions o;
  o.spacing = 0.8;
  const SectionLines r = ExtractSectionLines(o, HillPoints(23));
  EXPECT_EQ(r.spacing, 0.8);
  EXPECT_DOUBLE_EQ(r.max_gap, 4.8);
  EXPECT_DOUBLE_EQ(r.min_length, 1.6);
  ASSERT_EQ(r.lines.size(), 1u);
  EXPECT_NEAR(static_cast<double>(r.lines[0].points.size()), LineLength(r.lines[0]) / 0.8, 3);
  EXPECT_LE(Measure(r.lines[0], DistanceToHill).max, 0.01);
}

TEST(ExtractSectionLines, DeterministicAndOrderIndependent) {
  std::vector<Eigen::Vector2d> points = HillPoints(29);
  Rng rng(31);
  Append(&points, Rectangle({20, 10}, {30, 14}, 5.0, 0.001, &rng));
  const SectionLines a = ExtractSectionLines({}, points);
  ExpectSameBytes(a, ExtractSectionLines({}, points));
  std::vector<Eigen::Vector2d> shuffled = points;
  for (size_t i = shuffled.size() - 1; i > 0; --i) {
    std::swap(shuffled[i], shuffled[rng.Below(i + 1)]);
  }
  ExpectSameBytes(a, ExtractSectionLines({}, shuffled));
  std::reverse(shuffled.begin(), shuffled.end());
  ExpectSameBytes(a, ExtractSectionLines({}, shuffled));
}

// Timing, run by hand: --gtest_also_run_disabled_tests --gtest_filter='*TenMillion*'.
TEST(ExtractSectionLines, DISABLED_TenMillionPoints) {
  Rng rng(37);
  std::vector<Eigen::Vector2d> points;
  for (int k = 0; k < 50; ++k) {  // 50 hills 200 m long, 1000 points/m
    const double offset = 10.0 * k;
    Append(&points,
           SampleCurve([&](double t) { return Eigen::Vector2d(200 * t, offset + Hill(200 * t)); },
                       950.0, 0.001, &rng));
  }
  const auto start = std::chrono::steady_clock::now();
  const SectionLines r = ExtractSectionLines({}, points);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("%zu points: %zu lines, spacing %.4f m, %.2f s\n", r.points, r.lines.size(),
              r.spacing, seconds);
  EXPECT_EQ(r.lines.size(), 50u);
}

}  // namespace
}  // namespace candi::section

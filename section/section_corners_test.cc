#include "section/section_corners.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/polyline.h"
#include "core/rng.h"
#include "section/section_dxf.h"
#include "section/section_lines.h"

namespace candi::section {
namespace {

// Points on a curve (given densely as a polyline), uniform along it at `per_metre`, seeded, 1 mm
// noise across.
std::vector<Eigen::Vector2d> Sample(const std::vector<Eigen::Vector2d>& curve, double per_metre, uint64_t seed) {
  std::vector<double> s = {0};
  for (size_t i = 0; i + 1 < curve.size(); ++i) s.push_back(s.back() + (curve[i + 1] - curve[i]).norm());
  Rng rng(seed);
  std::vector<Eigen::Vector2d> out;
  const int n = static_cast<int>(std::round(s.back() * per_metre));
  for (int k = 0; k < n; ++k) {
    const double at = rng.Uniform(0, s.back());
    const size_t i = std::min<size_t>(std::upper_bound(s.begin(), s.end(), at) - s.begin() - 1, curve.size() - 2);
    const Eigen::Vector2d d = curve[i + 1] - curve[i];
    const Eigen::Vector2d normal(-d.y() / d.norm(), d.x() / d.norm());
    out.push_back(curve[i] + (at - s[i]) / d.norm() * d + 0.001 * rng.Normal() * normal);
  }
  return out;
}

// A ridge: two straight slopes meeting at an apex (a 25 degree turn), 5 points per metre. The
// extracted line cuts the apex; the corner pass puts a vertex on it.
TEST(RefineSectionCorners, PutsAVertexOnARidge) {
  const std::vector<Eigen::Vector2d> ridge = {{-20, -6}, {0, 0}, {20, -2}};
  const std::vector<Eigen::Vector2d> points = Sample(ridge, 5, 7);
  SectionLines lines = ExtractSectionLines({}, points);
  ASSERT_EQ(lines.lines.size(), 1u);
  auto apex_error = [&](const std::vector<Polyline2>& l) { return DistanceToPolyline(Eigen::Vector2d(0, 0), l[0].points); };
  const double before = apex_error(lines.lines);
  const SectionCornerSummary s = RefineSectionCorners({}, points, lines.spacing, &lines.lines);
  const double after = apex_error(lines.lines);
  std::printf("ridge apex: %.2f mm from the line before, %.2f mm after (%zu corner)\n", 1e3 * before, 1e3 * after,
              s.corners);
  EXPECT_EQ(s.corners, 1u);
  EXPECT_LT(after, 0.004);
  EXPECT_LT(after, before);
  // The other vertices stay where the extraction put them (those within a few spacings of the
  // apex keep the extraction's bias of a centimetre or two: see the README's limits).
  double worst = 0;
  for (const Eigen::Vector2d& v : lines.lines[0].points) {
    if (v.norm() > 2) worst = std::max(worst, DistanceToPolyline(v, ridge));
  }
  EXPECT_LT(worst, 0.005);
}

// A smooth arc (R = 15 m) has no corner: nothing moves.
TEST(RefineSectionCorners, LeavesSmoothCurvesAlone) {
  std::vector<Eigen::Vector2d> arc;
  for (int k = 0; k <= 600; ++k) {
    const double a = M_PI * k / 600;
    arc.push_back({15 * std::cos(a), 15 * std::sin(a)});
  }
  const std::vector<Eigen::Vector2d> points = Sample(arc, 5, 3);
  SectionLines lines = ExtractSectionLines({}, points);
  ASSERT_FALSE(lines.lines.empty());
  const std::vector<Polyline2> before = lines.lines;
  const SectionCornerSummary s = RefineSectionCorners({}, points, lines.spacing, &lines.lines);
  EXPECT_EQ(s.corners, 0u);
  ASSERT_EQ(lines.lines.size(), before.size());
  EXPECT_EQ(lines.lines[0].points, before[0].points);
}

TEST(SectionModuleOptions, DefaultsPassCheck) {
  EXPECT_NO_THROW(SectionCornerOptions().Check());
  EXPECT_NO_THROW(SectionLineOptions().Check());
  EXPECT_NO_THROW(DxfWriteOptions().Check());  // every value is valid
}

TEST(RefineSectionCorners, OptionsAreChecked) {
  EXPECT_NO_THROW(SectionCornerOptions{}.Check());
  SectionCornerOptions o;
  o.gain = 0;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = {};
  o.window = 0.5;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  // Nothing to refine: no points, no spacing.
  std::vector<Polyline2> none;
  EXPECT_EQ(RefineSectionCorners({}, {}, 0.5, &none).corners, 0u);
}

}  // namespace
}  // namespace candi::section

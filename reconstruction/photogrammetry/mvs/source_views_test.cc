#include "reconstruction/photogrammetry/mvs/source_views.h"

#include <cmath>
#include <stdexcept>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "tests/util/option_check.h"

namespace candi::photogrammetry {
namespace {

// A camera at `centre` looking at the origin (+z forward), 640 x 480, f = 500.
PinholeCamera LookAtOrigin(const Eigen::Vector3d& centre) {
  PinholeCamera c;
  c.width = 640, c.height = 480, c.fx = c.fy = 500, c.cx = 320, c.cy = 240;
  const Eigen::Vector3d z = (-centre).normalized();
  const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  c.rotation.row(0) = x.transpose(), c.rotation.row(1) = y.transpose(), c.rotation.row(2) = z.transpose();
  c.translation = -c.rotation * centre;
  return c;
}

Eigen::Vector3d OnArc(double degrees, double radius) {
  const double a = degrees * 3.14159265358979323846 / 180;
  return {radius * std::sin(a), 0, -radius * std::cos(a)};
}

TEST(SourceViews, OptionsAreChecked) {
  testing::ExpectEachBreakRejected<SourceViewOptions>({}, {
      [](SourceViewOptions& o) { o.num_sources = 0; },
      [](SourceViewOptions& o) { o.num_sources = 33; },
      [](SourceViewOptions& o) { o.num_check_views = 3; },
      [](SourceViewOptions& o) { o.num_check_views = 65; },
      [](SourceViewOptions& o) { o.min_triangulation_angle_deg = 60; },
      [](SourceViewOptions& o) { o.max_distance_ratio = 0.5; },
      [](SourceViewOptions& o) { o.max_distance_ratio = NAN; },
  });
}

TEST(SourceViews, TheTracksRankByPointsSharedAfterTheAngleAndDistanceRules) {
  // Cameras on an arc of radius 10 around points near the origin: 0 at 0 deg, 1 at 0.5 deg (too
  // small an angle), 2 at 10 deg, 3 at 20 deg, 4 at 30 deg but 30 m away (distance ratio 3), 5 at
  // -15 deg.
  const std::vector<PinholeCamera> cameras = {LookAtOrigin(OnArc(0, 10)),  LookAtOrigin(OnArc(0.5, 10)),
                                              LookAtOrigin(OnArc(10, 10)), LookAtOrigin(OnArc(20, 10)),
                                              LookAtOrigin(OnArc(30, 30)), LookAtOrigin(OnArc(-15, 10))};
  std::vector<Eigen::Vector3d> points;
  std::vector<std::vector<int>> tracks;
  // Photo 0 shares 40 points with 1 and 4, 30 with 2, 20 with 3 and 5; 2 and 3 share 10.
  auto add = [&](int count, std::vector<int> views) {
    for (int k = 0; k < count; ++k) {
      points.push_back(Eigen::Vector3d(0.01 * k, 0.02 * (k % 5), 0.03 * (k % 3)));
      tracks.push_back(views);
    }
  };
  add(40, {0, 1, 4});
  add(30, {0, 2, 2});  // a duplicate observation counts once
  add(20, {0, 3, 5});
  add(10, {2, 3});
  SourceViewOptions o;
  o.num_sources = 2;
  o.num_check_views = 3;
  const std::vector<ViewLinks> links = SelectSourceViewsFromTracks(o, cameras, points, tracks);
  ASSERT_EQ(links.size(), 6u);
  EXPECT_EQ(links[0].sources, (std::vector<int>{2, 3}));  // 1: angle 0.5 deg; 4: 3 times as far; 3 before 5
  EXPECT_EQ(links[0].checks, (std::vector<int>{2, 3, 5}));
  EXPECT_EQ(links[1].sources, std::vector<int>{});        // only 0 and 4 share its points; both fail
  EXPECT_EQ(links[1].checks, std::vector<int>{});
  EXPECT_EQ(links[2].sources, (std::vector<int>{0, 3}));
  EXPECT_EQ(links[3].sources, (std::vector<int>{0, 5}));  // 0 and 5 share 20 with it, 2 only 10
  EXPECT_EQ(links[3].checks, (std::vector<int>{0, 5, 2}));
  o.max_distance_ratio = 4;
  EXPECT_EQ(SelectSourceViewsFromTracks(o, cameras, points, tracks)[0].sources, (std::vector<int>{4, 2}));
  o.min_triangulation_angle_deg = 0;
  o.num_sources = 32;
  o.num_check_views = 32;
  EXPECT_EQ(SelectSourceViewsFromTracks(o, cameras, points, tracks)[0].sources, (std::vector<int>{1, 4, 2, 3, 5}));
  // A NaN point is skipped; a track naming a photo that is not there is a caller's error.
  points.push_back(Eigen::Vector3d(NAN, 0, 0));
  tracks.push_back({0, 3});
  EXPECT_EQ(SelectSourceViewsFromTracks(o, cameras, points, tracks)[0].checks, (std::vector<int>{1, 4, 2, 3, 5}));
  tracks.back() = {0, 9};
  points.back() = Eigen::Vector3d::Zero();
  EXPECT_THROW(SelectSourceViewsFromTracks(o, cameras, points, tracks), InternalError);
}

TEST(SourceViews, NeighboursAreSymmetricAndTheConfigIsColmaps) {
  const std::vector<std::vector<int>> sources = {{1, 2}, {0}, {}, {0}};
  EXPECT_EQ(NeighbourViews(sources), (std::vector<std::vector<int>>{{1, 2, 3}, {0}, {0}, {0}}));
  std::vector<ViewLinks> links;
  for (const std::vector<int>& s : sources) links.push_back({s, {}});
  links[2].checks = {1, 3};  // the check views join the neighbours, both ways
  EXPECT_EQ(NeighbourViews(links), (std::vector<std::vector<int>>{{1, 2, 3}, {0, 2}, {0, 1, 3}, {0, 2}}));
  EXPECT_EQ(PatchMatchConfig({"a.jpg", "b.jpg", "c.jpg", "d/e.jpg"}, links),
            "a.jpg\nb.jpg, c.jpg\nb.jpg\na.jpg\nc.jpg\n\nd/e.jpg\na.jpg\n");
  EXPECT_THROW(NeighbourViews(std::vector<std::vector<int>>{{0}}), InternalError);  // a photo its own source
}

TEST(SourceViews, WithoutTracksTheAngleAtTheOpticalAxisRules) {
  const std::vector<PinholeCamera> cameras = {LookAtOrigin(OnArc(0, 10)), LookAtOrigin(OnArc(1, 10)),
                                              LookAtOrigin(OnArc(14, 10)), LookAtOrigin(OnArc(40, 10)),
                                              LookAtOrigin(OnArc(180, 10))};
  SourceViewOptions o;
  o.num_sources = 3;
  o.num_check_views = 3;
  // 1: 1 deg, below 2; 4: 180 deg, above 75; 2 (14 deg) nearer 15 than 3 (40 deg). The check
  // views go on with the others in index order.
  const ViewLinks links = SelectSourceViewsByAngle(o, cameras, 0, 10.0);
  EXPECT_EQ(links.sources, (std::vector<int>{2, 3}));
  EXPECT_EQ(links.checks, (std::vector<int>{2, 3, 1}));
}

}  // namespace
}  // namespace candi::photogrammetry

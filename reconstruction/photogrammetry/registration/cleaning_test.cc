#include "reconstruction/photogrammetry/registration/cleaning.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <set>

#include "core/rng.h"
#include "tests/util/input_error.h"
#include "tests/util/surface_cloud.h"

namespace candi::photogrammetry {
namespace {

using testing::SurfaceCloud;
using testing::SurfaceCloudSpec;

// Appends `count` outliers 0.5-2 m above or below the surface, their id = 1e6 + k.
void InjectOutliers(PointCloud* cloud, size_t count, uint64_t seed) {
  Rng rng(seed);
  for (size_t k = 0; k < count; ++k) {
    const double x = rng.Uniform(0, 10), y = rng.Uniform(0, 10);
    const double off = rng.Uniform(0.5, 2.0) * (rng.Uniform() < 0.5 ? -1 : 1);
    const size_t i = cloud->size();
    cloud->Resize(i + 1);
    cloud->positions[i] = Eigen::Vector3d(x, y, testing::SurfaceHeight(x, y) + off);
    cloud->normals[i] = Eigen::Vector3f::UnitZ();
    cloud->colors[i] = Rgb8{255, 0, 0};
    cloud->scalars[0].f64[i] = 1e6 + static_cast<double>(k);
  }
}

PointCloud GridCloud(int nx, int ny, int nz, double spacing, const Eigen::Vector3d& origin) {
  PointCloud cloud;
  cloud.frame.origin = origin;
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      for (int k = 0; k < nz; ++k) {
        cloud.positions.emplace_back((i + 0.5) * spacing, (j + 0.5) * spacing, (k + 0.5) * spacing);
      }
    }
  }
  return cloud;
}

TEST(CleanOptions, DefaultsPassAndBadValuesNameTheField) {
  CleanOptions o;
  EXPECT_NO_THROW(o.Check());
  o.sor_neighbours = 0;
  try {
    o.Check();
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("sor_neighbours = 0"), std::string::npos) << e.what();
  }
  o = CleanOptions();
  o.sor_std_multiplier = -1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
  o = CleanOptions();
  o.voxel = -0.1;
  EXPECT_THROW(o.Check(), std::invalid_argument);
}

TEST(CleanPointCloud, InjectedOutliersGoAndInliersStayWithTheirAttributes) {
  SurfaceCloudSpec spec;
  spec.noise = 0.002;
  spec.origin = Eigen::Vector3d(416000.0, 9168000.0, 250.0);
  PointCloud cloud = SurfaceCloud(spec);
  const PointCloud inliers = cloud;
  InjectOutliers(&cloud, 200, 7);
  const CleanResult r = CleanPointCloud({}, cloud);
  size_t outliers_left = 0, inliers_kept = 0;
  for (size_t i = 0; i < r.cloud.size(); ++i) {
    const double id = r.cloud.scalars[0].f64[i];
    if (id >= 1e6) {
      ++outliers_left;
      continue;
    }
    ++inliers_kept;
    const size_t j = static_cast<size_t>(id);
    ASSERT_EQ(r.cloud.positions[i], inliers.positions[j]);
    ASSERT_EQ(r.cloud.colors[i], inliers.colors[j]);
    ASSERT_EQ(r.cloud.normals[i], inliers.normals[j]);
    ASSERT_EQ(r.cloud.layers[i], inliers.layers[j]);
  }
  EXPECT_EQ(outliers_left, 0u);
  EXPECT_GE(inliers_kept, static_cast<size_t>(0.99 * inliers.size()));
  EXPECT_EQ(r.summary.input, cloud.size());
  EXPECT_EQ(r.summary.outliers, cloud.size() - r.cloud.size());
  EXPECT_EQ(r.summary.output, r.cloud.size());
  EXPECT_EQ(r.cloud.frame, cloud.frame);
  EXPECT_EQ(r.cloud.schema, cloud.schema);
  // Kept points stay in input order.
  for (size_t i = 1; i < r.cloud.size(); ++i) {
    ASSERT_LT(r.cloud.scalars[0].f64[i - 1], r.cloud.scalars[0].f64[i]);
  }
}

TEST(CleanPointCloud, SurveyCoordinatesGiveTheSameInliersAsNearTheOrigin) {
  SurfaceCloudSpec spec;
  spec.count = 5000;
  spec.noise = 0.001;
  PointCloud near = SurfaceCloud(spec);
  InjectOutliers(&near, 50, 8);
  PointCloud far = near;
  far.frame.origin = Eigen::Vector3d(416000.0, 9168000.0, 0.0);
  far.Rebase(LocalFrame{});  // positions now hold the survey coordinates themselves
  EXPECT_EQ(StatisticalInliers(near, 16, 3.0), StatisticalInliers(far, 16, 3.0));
}

TEST(VoxelThinIndices, AGridGivesExactCountsAndOnePointPerVoxel) {
  const double leaf = 0.2;
  for (const Eigen::Vector3d& origin :
       {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(416000, 9168000, 0)}) {
    const PointCloud grid = GridCloud(20, 20, 5, 0.1, origin);  // 2000 points, 2 per cell and axis
    const std::vector<size_t> kept = VoxelThinIndices(grid, leaf);
    EXPECT_EQ(kept.size(), 10u * 10u * 3u);  // z: 5 points fill 2 + 2 + 1 cells
    std::set<std::array<int64_t, 3>> cells;
    for (size_t i : kept) {
      const Eigen::Vector3d w = grid.WorldPosition(i);
      const std::array<int64_t, 3> cell{static_cast<int64_t>(std::floor(w.x() / leaf)),
                                        static_cast<int64_t>(std::floor(w.y() / leaf)),
                                        static_cast<int64_t>(std::floor(w.z() / leaf))};
      EXPECT_TRUE(cells.insert(cell).second) << "two points in one voxel";
    }
  }
}

TEST(VoxelThinIndices, KeepsThePointNearestTheVoxelCentre) {
  PointCloud cloud;
  cloud.positions = {{0.01, 0.01, 0.01}, {0.09, 0.11, 0.12}, {0.05, 0.05, 0.05}, {0.3, 0.1, 0.1}};
  EXPECT_EQ(VoxelThinIndices(cloud, 0.2), (std::vector<size_t>{1, 3}));
}

TEST(VoxelThinIndices, HugeExtentWithATinyLeafDoesNotOverflow) {
  PointCloud cloud;
  cloud.positions = {{-5e6, -9e6, 0}, {5e6 + 3e-7, 9e6, 100}, {5e6 + 6e-7, 9e6, 100},
                     {5e6 + 3.5e-6, 9e6, 100}};
  // 1e13 cells per axis: beyond PCL VoxelGrid's 32-bit index; points 3e-7 apart share a cell.
  EXPECT_EQ(VoxelThinIndices(cloud, 1e-6).size(), 3u);
  EXPECT_THROW(VoxelThinIndices(cloud, 1e-300), std::invalid_argument);
}

TEST(CleanPointCloud, EmptyAndNonFiniteInputs) {
  PointCloud empty;
  CleanOptions o;
  o.voxel = 0.1;
  const CleanResult r = CleanPointCloud(o, empty);
  EXPECT_TRUE(r.cloud.empty());
  EXPECT_EQ(r.summary.input, 0u);
  EXPECT_EQ(r.summary.output, 0u);
  SurfaceCloudSpec spec;
  spec.count = 1000;
  PointCloud cloud = SurfaceCloud(spec);
  cloud.positions[3].x() = std::numeric_limits<double>::quiet_NaN();
  cloud.positions[9].z() = std::numeric_limits<double>::infinity();
  const CleanResult c = CleanPointCloud(o, cloud);
  EXPECT_EQ(c.summary.non_finite, 2u);
  EXPECT_EQ(c.summary.input, 1000u);
  EXPECT_EQ(c.summary.output + c.summary.thinned + c.summary.outliers + 2, 1000u);
  for (const Eigen::Vector3d& p : c.cloud.positions) EXPECT_TRUE(p.allFinite());
  // The lower-level steps refuse non-finite positions with the point's index.
  EXPECT_NE(testing::InputErrorMessage([&] { VoxelThinIndices(cloud, 0.1); }).find("point 3"),
            std::string::npos);
  EXPECT_NE(testing::InputErrorMessage([&] { StatisticalInliers(cloud, 8, 2.0); }).find("point 3"),
            std::string::npos);
}

TEST(CleanPointCloud, VoxelThinningAfterSorIsDeterministicAndCounted) {
  SurfaceCloudSpec spec;
  spec.count = 5000;
  PointCloud cloud = SurfaceCloud(spec);
  InjectOutliers(&cloud, 20, 9);
  CleanOptions o;
  o.voxel = 0.25;
  const CleanResult a = CleanPointCloud(o, cloud);
  const CleanResult b = CleanPointCloud(o, cloud);
  EXPECT_EQ(a.cloud.positions, b.cloud.positions);
  EXPECT_GT(a.summary.thinned, 0u);
  EXPECT_EQ(a.summary.input - a.summary.outliers - a.summary.thinned, a.summary.output);
  o.sor = false;
  const CleanResult c = CleanPointCloud(o, cloud);
  EXPECT_EQ(c.summary.outliers, 0u);
}

}  // namespace
}  // namespace candi::photogrammetry

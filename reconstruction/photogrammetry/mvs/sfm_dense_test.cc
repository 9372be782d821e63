// End to end on the synthetic scene: photos the project renders itself -> COLMAP SfM (run for
// real, as `candi sfm` runs it) -> candi's PatchMatch stereo and fusion on COLMAP's undistorted
// workspace (as `candi dense` reads it) -> the cloud, moved into the scene's frame by the
// similarity between the recovered and the true camera centres, scored against the true surface.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <map>

#include "reconstruction/photogrammetry/georef/similarity_fit.h"
#include "reconstruction/photogrammetry/mvs/dense_workspace.h"
#include "reconstruction/photogrammetry/mvs/fusion.h"
#include "reconstruction/photogrammetry/mvs/patch_match.h"
#include "reconstruction/photogrammetry/registration/point_index.h"
#include "reconstruction/photogrammetry/scenes/synthetic_views.h"
#include "reconstruction/photogrammetry/sfm/colmap_runner.h"
#include "tests/util/test_util.h"

namespace candi::photogrammetry {
namespace {

using candi::testing::RunCommand;
using candi::testing::TempDir;

double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// True surface points seen by view k at every `stride`-th pixel that at least one other view also
// sees (in its frame, unoccluded): the part of the surface stereo can recover.
std::vector<Eigen::Vector3d> ObservableSurface(const std::vector<SyntheticView>& views, int stride) {
  std::vector<Eigen::Vector3d> out;
  for (size_t k = 0; k < views.size(); ++k) {
    const SyntheticView& v = views[k];
    for (int y = stride / 2; y < v.depth.height(); y += stride) {
      for (int x = stride / 2; x < v.depth.width(); x += stride) {
        const double t = v.depth.at(x, y);
        if (!(t > 0)) continue;
        const Eigen::Vector3d X = v.camera.ToWorld(t * v.camera.Ray(x + 0.5, y + 0.5));
        bool seen = false;
        for (size_t j = 0; j < views.size() && !seen; ++j) {
          if (j == k) continue;
          const Eigen::Vector3d c = views[j].camera.ToCamera(X);
          if (!(c.z() > 0)) continue;
          const Eigen::Vector2d uv = views[j].camera.Project(c);
          if (!(uv.x() >= 0 && uv.y() >= 0 && uv.x() < views[j].camera.width && uv.y() < views[j].camera.height)) continue;
          const double hit = SyntheticSceneRayHit(views[j].camera.Center(), X - views[j].camera.Center());
          seen = hit > 0 && std::abs(1.0 - hit) < 1e-3;
        }
        if (seen) out.push_back(X);
      }
    }
  }
  return out;
}

struct EndToEnd {
  int views, width, height;
  double arc_degrees;
  int iterations;
  int source_views;
  double resolution_scale;  // dense working resolution
  std::string camera_model;
  double tolerance;         // accuracy: relative depth error; completeness: that times 5.5 m
  double min_accuracy, min_completeness;
};

// Photos of the scene (PNG: no EXIF, so COLMAP must find the shared SIMPLE_RADIAL camera's focal)
// through SfM and dense stereo; asserts registration, camera centres, accuracy and completeness.
void RunEndToEnd(const EndToEnd& c) {
  if (RunCommand("colmap help").code != 0) GTEST_SKIP() << "COLMAP is not installed here (Debian: apt install colmap)";
  TempDir dir;
  SyntheticViewsOptions scene;
  scene.views = c.views;
  scene.width = c.width;
  scene.height = c.height;
  scene.arc_degrees = c.arc_degrees;
  scene.supersample = 2;
  scene.texture_cell = 0.03;
  const std::vector<SyntheticView> views = RenderSyntheticViews(scene);
  WriteSyntheticImages(views, dir.File("photos"));

  auto t0 = std::chrono::steady_clock::now();
  SfmOptions sfm;
  sfm.threads = 2;
  sfm.max_image_size = std::max(c.width, c.height);
  sfm.camera_model = c.camera_model;
  const SfmSummary summary = RunSfm(sfm, dir.File("photos"), dir.File("work"));
  const double sfm_s = SecondsSince(t0);
  EXPECT_GE(summary.registered.size(), views.size() - 1) << "registered " << summary.registered.size();
  EXPECT_LT(summary.mean_reprojection_error, 1.0);

  t0 = std::chrono::steady_clock::now();
  const StereoInput input = ReadDenseWorkspace(summary.dense_dir);
  ASSERT_EQ(input.images.size(), summary.registered.size());
  PatchMatchOptions pm;
  pm.threads = 2;
  pm.iterations = c.iterations;
  pm.num_source_views = c.source_views;
  pm.resolution_scale = c.resolution_scale;
  const PatchMatchResult stereo = RunPatchMatch(pm, input);
  const PointCloud cloud = FuseDepthMaps(FusionOptions(), stereo.maps);
  const double dense_s = SecondsSince(t0);
  ASSERT_GT(cloud.size(), 1000u);

  // The model's frame is arbitrary: the similarity from the recovered to the true camera centres.
  std::map<std::string, const SyntheticView*> by_name;
  for (const SyntheticView& v : views) by_name[v.name] = &v;
  std::vector<Eigen::Vector3d> model_centres, true_centres;
  for (const StereoImage& image : input.images) {
    ASSERT_TRUE(by_name.count(image.name)) << image.name;
    model_centres.push_back(image.camera.Center());
    true_centres.push_back(by_name[image.name]->camera.Center());
  }
  const Sim3 world_from_model =
      UmeyamaSimilarity(model_centres, true_centres, std::vector<double>(model_centres.size(), 1.0), true);
  double centre_rms = 0;
  for (size_t i = 0; i < model_centres.size(); ++i) {
    centre_rms += (world_from_model * model_centres[i] - true_centres[i]).squaredNorm();
  }
  centre_rms = std::sqrt(centre_rms / model_centres.size());
  EXPECT_LT(centre_rms, 0.01) << "camera centres after the similarity, m (the arc's radius is 5.5 m)";

  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3f> points_f;
  for (size_t i = 0; i < cloud.size(); ++i) {
    points.push_back(world_from_model * cloud.WorldPosition(i));
    points_f.push_back(points.back().cast<float>());
  }
  // Accuracy: points within 1 % of the depth along a viewing ray (ScoreSyntheticDense; its
  // per-pixel completeness needs maps on the true cameras' pixel grids, so it is not used here).
  const SyntheticDenseScore score =
      ScoreSyntheticDense(views, std::vector<ImageF>(views.size()), points, c.tolerance);
  // Completeness: observable surface samples with a dense point within the tolerance times the
  // camera distance.
  const std::vector<Eigen::Vector3d> surface = ObservableSurface(views, 4);
  std::vector<Eigen::Vector3f> queries;
  for (const auto& p : surface) queries.push_back(p.cast<float>());
  const PointIndex index(points_f);
  const OverlapStats overlap = MeasureOverlap(index, queries, Eigen::Matrix4d::Identity(), c.tolerance * scene.distance);
  std::printf("focal: recovered %.2f px (undistorted %dx%d), true %.2f px\n", input.images[0].camera.fx,
              input.images[0].camera.width, input.images[0].camera.height, views[0].camera.fx);
  std::printf("%d photos %dx%d: sfm %.1f s (%zu registered, reprojection %.3f px); dense %.1f s, %zu points; "
              "camera centres RMS %.4f m; accuracy %.3f (median relative error %.5f); completeness %.3f "
              "of %zu observable samples\n",
              c.views, c.width, c.height, sfm_s, summary.registered.size(), summary.mean_reprojection_error,
              dense_s, cloud.size(), centre_rms, score.accuracy, score.median_error, overlap.overlap,
              surface.size());
  EXPECT_GE(score.accuracy, c.min_accuracy);
  EXPECT_GE(overlap.overlap, c.min_completeness);
}

// The CI-sized run: eight 320x240 photos on a 70-degree arc.
TEST(SfmDense, SyntheticPhotosReconstructAccuratelyAndCompletely) { RunEndToEnd({8, 400, 300, 80, 2, 3, 0.5, "SIMPLE_PINHOLE", 0.02, 0.8, 0.6}); }

// Twelve 480x360 photos on a 100-degree arc, three PatchMatch rounds: ~11 CPU-minutes. Measured
// 2026-11-22: 12 of 12 registered, 0.128 px, camera centres RMS 0.8 mm, accuracy 0.997,
// completeness 0.839.
TEST(SfmDense, LargerSyntheticSet) {
  CANDI_REQUIRE_SLOW_TESTS();
  RunEndToEnd({12, 480, 360, 100, 3, 4, 1.0, "SIMPLE_RADIAL", 0.01, 0.9, 0.7});
}

}  // namespace
}  // namespace candi::photogrammetry

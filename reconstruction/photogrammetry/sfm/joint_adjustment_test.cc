#include "reconstruction/photogrammetry/sfm/joint_adjustment.h"

#include <cmath>
#include <map>
#include <random>

#include <gtest/gtest.h>

#include "core/check.h"
#include "core/transform.h"
#include "reconstruction/photogrammetry/scenes/campaign.h"
#include "reconstruction/photogrammetry/sfm/chunked_mapping.h"

namespace candi::photogrammetry {
namespace {

// A campaign's truth as the merged model of its three chunks, each tied with an error of its own
// (a similarity of a few millimetres): the sparse points are wall points that two or more photos
// see (observed with 0.3 px noise), each chunk triangulating its own copy from its own photos;
// the targets are picked (0.3 px) wherever a photo sees them. World = the model's frame.
struct TiedCampaign {
  ColmapModel model;
  std::vector<PairMatches> matches;  // every photo pair sharing a point, inliers by keypoint
  std::vector<SurveyTarget> targets;
  std::vector<ImagePick> picks;
  std::map<std::string, Eigen::Vector3d> true_centres;  // by image name
};

// Where the camera sees a surface point, 2 px inside the frame; false where it does not.
bool SeenAt(const SyntheticScene& scene, const PinholeCamera& camera, const Eigen::Vector3d& x, Eigen::Vector2d* uv) {
  if (!scene.Sees(camera, x)) return false;
  *uv = camera.Project(camera.ToCamera(x));
  return uv->x() >= 2 && uv->y() >= 2 && uv->x() <= camera.width - 2 && uv->y() <= camera.height - 2;
}

TiedCampaign MakeTiedCampaign(const Campaign& c, const std::vector<Sim3>& tie_error) {
  TiedCampaign t;
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.3);
  std::map<std::string, uint32_t> chunk_camera;
  for (size_t k = 0; k < c.chunks.size(); ++k) {
    ColmapCamera camera;
    camera.camera_id = static_cast<uint32_t>(k + 1);
    camera.model = "PINHOLE";
    const PinholeCamera& p = c.photos.front().camera;
    camera.width = p.width, camera.height = p.height;
    camera.params = {p.fx, p.fy, p.cx, p.cy};
    t.model.cameras[camera.camera_id] = camera;
    chunk_camera[c.chunks[k]] = camera.camera_id;
  }
  std::map<std::string, size_t> chunk_index;
  for (size_t k = 0; k < c.chunks.size(); ++k) chunk_index[c.chunks[k]] = k;
  for (size_t i = 0; i < c.photos.size(); ++i) {
    const CampaignPhoto& p = c.photos[i];
    const Sim3& e = tie_error[chunk_index.at(p.chunk)];
    ColmapImage image;
    image.image_id = static_cast<uint32_t>(i + 1);
    image.camera_id = chunk_camera.at(p.chunk);
    image.name = p.chunk + "/" + p.name;
    const Eigen::Quaterniond r = Eigen::Quaterniond(p.camera.rotation) * e.rotation.conjugate();
    image.cam_from_world_rotation = r.normalized();
    image.cam_from_world_translation = e.scale * p.camera.translation - r * e.translation;
    t.model.images[image.image_id] = image;
    t.true_centres[image.name] = p.camera.Center();
  }
  // Wall points on a grid of each photo, and every photo that sees each.
  std::map<std::pair<uint32_t, uint32_t>, PairMatches> pairs;
  for (const CampaignPhoto& p : c.photos) {
    for (int gy = 1; gy <= 4; ++gy) {
      for (int gx = 1; gx <= 5; ++gx) {
        const Eigen::Vector3d dir =
            (p.camera.rotation.transpose() * p.camera.Ray(p.camera.width * gx / 6.0, p.camera.height * gy / 5.0))
                .normalized();
        const double hit = c.scene.RayHit(p.camera.Center(), dir);
        if (!(hit > 0)) continue;
        const Eigen::Vector3d x = p.camera.Center() + hit * dir;
        std::vector<std::pair<uint32_t, uint32_t>> seen;  // image id, keypoint
        std::map<std::string, std::vector<ColmapTrackElement>> by_chunk;
        for (size_t i = 0; i < c.photos.size(); ++i) {
          Eigen::Vector2d uv;
          if (!SeenAt(c.scene, c.photos[i].camera, x, &uv)) continue;
          ColmapImage& image = t.model.images.at(static_cast<uint32_t>(i + 1));
          const uint32_t keypoint = static_cast<uint32_t>(image.points2d.size());
          image.points2d.push_back(uv + Eigen::Vector2d(noise(rng), noise(rng)));
          image.point3d_ids.push_back(kInvalidPoint3dId);
          seen.push_back({image.image_id, keypoint});
          by_chunk[c.photos[i].chunk].push_back({image.image_id, keypoint});
        }
        for (const auto& [chunk, track] : by_chunk) {
          if (track.size() < 2) continue;
          ColmapPoint3d point;
          point.point3d_id = t.model.points3d.size() + 1;
          point.xyz = tie_error[chunk_index.at(chunk)] * x;
          point.track = track;
          for (const ColmapTrackElement& e : track) t.model.images.at(e.image_id).point3d_ids[e.point2d_idx] = point.point3d_id;
          t.model.points3d[point.point3d_id] = point;
        }
        for (size_t a = 0; a < seen.size(); ++a) {
          for (size_t b = a + 1; b < seen.size(); ++b) {
            PairMatches& m = pairs[{seen[a].first, seen[b].first}];
            m.image_a = t.model.images.at(seen[a].first).name;
            m.image_b = t.model.images.at(seen[b].first).name;
            m.matches.push_back({seen[a].second, seen[b].second});
          }
        }
      }
    }
  }
  for (auto& [ids, m] : pairs) t.matches.push_back(std::move(m));
  for (const CampaignTarget& target : c.targets) {
    SurveyTarget s;
    s.name = target.name;
    s.survey = target.center;
    s.role = target.check ? TargetRole::kCheck : TargetRole::kControl;
    s.accuracy = 0.001;
    t.targets.push_back(s);
    for (const CampaignPhoto& p : c.photos) {
      Eigen::Vector2d uv;
      if (SeenAt(c.scene, p.camera, target.center, &uv)) {
        t.picks.push_back({target.name, p.name, uv + Eigen::Vector2d(noise(rng), noise(rng)), 0});
      }
    }
  }
  return t;
}

double CentreRms(const ColmapModel& model, const std::map<std::string, Eigen::Vector3d>& truth) {
  double sum = 0;
  for (const auto& [id, image] : model.images) {
    const Eigen::Vector3d centre =
        -(image.cam_from_world_rotation.conjugate() * image.cam_from_world_translation);
    sum += (centre - truth.at(image.name)).squaredNorm();
  }
  return std::sqrt(sum / model.images.size());
}

Campaign ThreeSessionPlan() {
  CampaignOptions o;
  o.photos = 45;
  o.width = 320;
  o.chunks = 3;
  return PlanCampaign(o);
}

std::vector<Sim3> TieErrors() {
  return {Sim3(1.002, Eigen::Quaterniond(Eigen::AngleAxisd(0.002, Eigen::Vector3d(0, 0, 1))), Eigen::Vector3d(0.006, -0.004, 0.003)),
          Sim3(0.998, Eigen::Quaterniond(Eigen::AngleAxisd(-0.002, Eigen::Vector3d(1, 0, 0))), Eigen::Vector3d(-0.005, 0.007, -0.002)),
          Sim3(1.001, Eigen::Quaterniond(Eigen::AngleAxisd(0.0015, Eigen::Vector3d(0, 1, 0))), Eigen::Vector3d(0.002, 0.004, 0.008))};
}

// Three chunks tied with errors of several millimetres each: adjusted as one, their points joined
// where the photos' matches link them, the cameras come to the truth within the noise.
TEST(JointAdjustment, BringsChunksTiedWithErrorsOfTheirOwnTogether) {
  const Campaign c = ThreeSessionPlan();
  TiedCampaign t = MakeTiedCampaign(c, TieErrors());
  const double before = CentreRms(t.model, t.true_centres);
  const size_t points_before = t.model.points3d.size();
  const JointAdjustmentResult r = AdjustJointly(&t.model, t.matches, t.targets, t.picks, JointAdjustmentOptions{});
  const double after = CentreRms(t.model, t.true_centres);
  std::printf("camera centres %.2f mm -> %.2f mm RMS; %zu links, %zu refused, %zu joined points; reprojection %.3f -> "
              "%.3f px; check %.2f mm (%d)\n",
              1e3 * before, 1e3 * after, r.links, r.links_rejected, r.joined_points, r.rms_before_px, r.rms_after_px,
              1e3 * r.check.d3, r.check.count);
  ASSERT_TRUE(r.ran);
  EXPECT_TRUE(r.converged);
  EXPECT_GT(before, 0.005);
  // Measured 15.9 -> 3.3 mm: what is left is the targets' pick noise (0.3 px of 7 mm at the wall).
  EXPECT_LT(after, 0.3 * before);
  EXPECT_LT(after, 0.005);
  EXPECT_GT(r.joined_points, 50u);
  EXPECT_EQ(t.model.points3d.size(), points_before - (r.links));  // each kept link joins two points into one
  EXPECT_EQ(r.links_rejected, 0u);  // every link is a true one here
  // Each chunk is whole in itself (its error is one similarity): 0.3 px per axis, 0.42 px, either way.
  EXPECT_LT(r.rms_before_px, 0.6);
  EXPECT_LT(r.rms_after_px, 0.6);
  EXPECT_GE(r.check.count, 2);
  EXPECT_LT(r.check.d3, 0.003);
  EXPECT_LT(r.control.d3, 0.003);
  // The model stays whole: every point's track points back at it.
  for (const auto& [id, point] : t.model.points3d) {
    for (const ColmapTrackElement& e : point.track) EXPECT_EQ(t.model.images.at(e.image_id).point3d_ids[e.point2d_idx], id);
  }
}

// The chunks' copies of one camera, adjusted as one: the model holds one camera, as good.
TEST(JointAdjustment, TheChunksCopiesOfOneCameraBecomeOne) {
  const Campaign c = ThreeSessionPlan();
  TiedCampaign t = MakeTiedCampaign(c, TieErrors());
  t.model.cameras.at(2).params[0] *= 1.004;  // the chunks' mappers disagree on the focal length
  JointAdjustmentOptions o;
  o.one_camera = true;
  const JointAdjustmentResult r = AdjustJointly(&t.model, t.matches, t.targets, t.picks, o);
  ASSERT_EQ(t.model.cameras.size(), 1u);
  for (const auto& [id, image] : t.model.images) EXPECT_EQ(image.camera_id, 1u);
  EXPECT_NEAR(t.model.cameras.at(1).params[0], c.photos.front().camera.fx, 0.002 * c.photos.front().camera.fx);
  EXPECT_LT(CentreRms(t.model, t.true_centres), 0.005);
  EXPECT_LT(r.rms_after_px, 0.6);
  // Copies that differ in size are not one camera: refused, the model untouched.
  TiedCampaign u = MakeTiedCampaign(c, TieErrors());
  u.model.cameras.at(3).width += 2;
  const ColmapModel before = u.model;
  EXPECT_THROW(AdjustJointly(&u.model, u.matches, u.targets, u.picks, o), InputError);
  EXPECT_EQ(u.model.points3d.size(), before.points3d.size());
}

// A match between two far-apart points (a wrong match that passed verification) is refused, as is
// one that would give a photo two observations of one point.
TEST(JointAdjustment, RefusesLinksBetweenFarPointsAndWithinOnePhoto) {
  const Campaign c = ThreeSessionPlan();
  TiedCampaign t = MakeTiedCampaign(c, TieErrors());
  // Two images of different chunks and their points farthest apart.
  const ColmapImage* a = nullptr;
  const ColmapImage* b = nullptr;
  for (const PairMatches& m : t.matches) {
    if (m.image_a.substr(0, 2) == m.image_b.substr(0, 2)) continue;
    for (const auto& [id, image] : t.model.images) {
      if (image.name == m.image_a) a = &image;
      if (image.name == m.image_b) b = &image;
    }
    break;
  }
  ASSERT_TRUE(a != nullptr && b != nullptr);
  uint32_t ka = 0, kb = 0;
  double far = 0;
  for (uint32_t i = 0; i < a->point3d_ids.size(); ++i) {
    for (uint32_t j = 0; j < b->point3d_ids.size(); ++j) {
      if (a->point3d_ids[i] == kInvalidPoint3dId || b->point3d_ids[j] == kInvalidPoint3dId) continue;
      const double d = (t.model.points3d.at(a->point3d_ids[i]).xyz - t.model.points3d.at(b->point3d_ids[j]).xyz).norm();
      if (d > far) far = d, ka = i, kb = j;
    }
  }
  ASSERT_GT(far, 0.2);
  const std::vector<PairMatches> wrong = {{a->name, b->name, {{ka, kb}}}};
  ColmapModel model = t.model;
  const JointAdjustmentResult r = AdjustJointly(&model, wrong, t.targets, t.picks, JointAdjustmentOptions{});
  EXPECT_EQ(r.links, 0u);
  EXPECT_EQ(r.links_rejected, 1u);
  EXPECT_EQ(model.points3d.size(), t.model.points3d.size());
  // Within one photo: a's two observations of different chunk points cannot become one point,
  // however close the points are allowed to be.
  JointAdjustmentOptions wide;
  wide.max_link_angle_deg = 89;
  uint32_t second = 0;
  for (uint32_t i = 0; i < a->point3d_ids.size(); ++i)
    if (i != ka && a->point3d_ids[i] != kInvalidPoint3dId) second = i;
  // Link a's point ka with b's kb, then b's kb with a's other point: the second would put two of
  // a's keypoints in one track.
  const std::vector<PairMatches> twice = {{a->name, b->name, {{ka, kb}, {second, kb}}}};
  model = t.model;
  const JointAdjustmentResult r2 = AdjustJointly(&model, twice, t.targets, t.picks, wide);
  EXPECT_EQ(r2.links, 1u);
  EXPECT_EQ(r2.links_rejected, 1u);
}

TEST(JointAdjustment, NeedsAControlTargetSeenTwiceAndAKnownCamera) {
  const Campaign c = ThreeSessionPlan();
  TiedCampaign t = MakeTiedCampaign(c, TieErrors());
  ColmapModel model = t.model;
  EXPECT_THROW(AdjustJointly(&model, t.matches, t.targets, {}, JointAdjustmentOptions{}), InputError);
  model.cameras.begin()->second.model = "OPENCV_FISHEYE";
  EXPECT_THROW(AdjustJointly(&model, t.matches, t.targets, t.picks, JointAdjustmentOptions{}), InputError);
  JointAdjustmentOptions bad;
  bad.max_link_angle_deg = 0;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

}  // namespace
}  // namespace candi::photogrammetry

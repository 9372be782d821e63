#include "reconstruction/photogrammetry/sfm/joint_adjustment.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <numeric>
#include <set>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "core/check.h"
#include "reconstruction/photogrammetry/sfm/camera_projection.h"
#include "reconstruction/photogrammetry/sfm/chunked_mapping.h"

namespace candi::photogrammetry {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kHuberSigmas = 2;  // a residual beyond 2 sigma weighs linearly

// A pixel observation of a point by a posed camera of kParams intrinsics, whitened by its standard
// deviation.
template <int kParams>
struct Reprojection {
  Reprojection(ProjectionModel model, const Eigen::Vector2d& observed, double sigma)
      : model(model), observed(observed), inverse_sigma(1 / sigma) {}
  template <typename T>
  bool operator()(const T* q, const T* t, const T* x, const T* intrinsics, T* residual) const {
    T p[3];
    ceres::UnitQuaternionRotatePoint(q, x, p);
    p[0] += t[0], p[1] += t[1], p[2] += t[2];
    if (!(p[2] > T(0))) return false;  // behind the camera: the step is refused
    T px(0), py(0);
    if (!PixelFromNormalized(model, intrinsics, p[0] / p[2], p[1] / p[2], &px, &py)) return false;
    residual[0] = (px - observed.x()) * inverse_sigma;
    residual[1] = (py - observed.y()) * inverse_sigma;
    return true;
  }
  ProjectionModel model;
  Eigen::Vector2d observed;
  double inverse_sigma;
};

template <int kParams>
ceres::CostFunction* Make(ProjectionModel model, const Eigen::Vector2d& observed, double sigma) {
  return new ceres::AutoDiffCostFunction<Reprojection<kParams>, 2, 4, 3, 3, kParams>(
      new Reprojection<kParams>(model, observed, sigma));
}

ceres::CostFunction* MakeReprojection(ProjectionModel model, const Eigen::Vector2d& observed, double sigma) {
  switch (ProjectionParams(model)) {
    case 3: return Make<3>(model, observed, sigma);
    case 4: return Make<4>(model, observed, sigma);
    case 5: return Make<5>(model, observed, sigma);
    case 8: return Make<8>(model, observed, sigma);
    case 12: return Make<12>(model, observed, sigma);
    default: break;
  }
  CANDI_CHECK(false);
  return nullptr;
}

// A control target held to its surveyed coordinates by their accuracy.
struct SurveyPrior {
  SurveyPrior(const Eigen::Vector3d& at, double sigma) : at(at), inverse_sigma(1 / sigma) {}
  template <typename T>
  bool operator()(const T* x, T* residual) const {
    for (int k = 0; k < 3; ++k) residual[k] = (x[k] - at[k]) * inverse_sigma;
    return true;
  }
  Eigen::Vector3d at;
  double inverse_sigma;
};

struct Pose {
  double q[4];  // w x y z (Ceres's order)
  double t[3];
};

Eigen::Vector3d Centre(const ColmapImage& image) {
  return -(image.cam_from_world_rotation.normalized().conjugate() * image.cam_from_world_translation);
}

double Angle(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Union-find over points, each root holding the sorted images its members are seen in.
class Tracks {
 public:
  explicit Tracks(std::vector<std::vector<uint32_t>> images) : parent_(images.size()), images_(std::move(images)) {
    std::iota(parent_.begin(), parent_.end(), size_t{0});
  }
  size_t Find(size_t i) {
    while (parent_[i] != i) i = parent_[i] = parent_[parent_[i]];
    return i;
  }
  // Joins the sets of a and b unless one photo sees both; false then.
  bool Join(size_t a, size_t b) {
    a = Find(a), b = Find(b);
    std::vector<uint32_t> both;
    std::set_intersection(images_[a].begin(), images_[a].end(), images_[b].begin(), images_[b].end(),
                          std::back_inserter(both));
    if (!both.empty()) return false;
    if (b < a) std::swap(a, b);  // the smaller index is the root: the result follows the input order only
    std::vector<uint32_t> merged;
    std::set_union(images_[a].begin(), images_[a].end(), images_[b].begin(), images_[b].end(),
                   std::back_inserter(merged));
    images_[a] = std::move(merged);
    images_[b].clear();
    parent_[b] = a;
    return true;
  }
  // Adds a photo to i's set unless it is there already; false then.
  bool AddImage(size_t i, uint32_t image) {
    std::vector<uint32_t>& set = images_[Find(i)];
    const auto at = std::lower_bound(set.begin(), set.end(), image);
    if (at != set.end() && *at == image) return false;
    set.insert(at, image);
    return true;
  }

 private:
  std::vector<size_t> parent_;
  std::vector<std::vector<uint32_t>> images_;
};

// A point's reprojection errors in the photos of its track (pixels), where it is in front of them.
std::vector<double> TrackErrors(const ColmapModel& model, const ColmapPoint3d& point) {
  std::vector<double> errors;
  for (const ColmapTrackElement& e : point.track) {
    const ColmapImage& image = model.images.at(e.image_id);
    const Eigen::Vector2d uv = ProjectToImage(model.cameras.at(image.camera_id), image, point.xyz);
    if (uv.allFinite()) errors.push_back((uv - image.points2d[e.point2d_idx]).norm());
  }
  return errors;
}

double MeanError(const ColmapModel& model, const ColmapPoint3d& point) {
  const std::vector<double> errors = TrackErrors(model, point);
  double sum = 0;
  for (double e : errors) sum += e;
  return errors.empty() ? -1.0 : sum / static_cast<double>(errors.size());
}

double RmsError(const ColmapModel& model) {
  double sum = 0;
  size_t n = 0;
  for (const auto& [id, point] : model.points3d) {
    for (double e : TrackErrors(model, point)) sum += e * e, ++n;
  }
  return n == 0 ? 0.0 : std::sqrt(sum / static_cast<double>(n));
}

}  // namespace

void JointAdjustmentOptions::Check() const {
  CANDI_CHECK_OPTION(max_link_angle_deg > 0 && max_link_angle_deg < 90, max_link_angle_deg, "in (0, 90) degrees");
  CANDI_CHECK_OPTION(reprojection_sigma_px > 0 && std::isfinite(reprojection_sigma_px), reprojection_sigma_px, "> 0");
  CANDI_CHECK_OPTION(pick_sigma_px > 0 && std::isfinite(pick_sigma_px), pick_sigma_px, "> 0");
  CANDI_CHECK_OPTION_GE(max_iterations, 1);
}

JointAdjustmentResult AdjustJointly(ColmapModel* model, const std::vector<PairMatches>& matches,
                                    const std::vector<SurveyTarget>& targets, const std::vector<ImagePick>& picks,
                                    const JointAdjustmentOptions& options) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  JointAdjustmentResult result;
  for (const auto& [id, camera] : model->cameras) {
    if (ProjectionModelOf(camera.model) == ProjectionModel::kUnsupported ||
        static_cast<int>(camera.params.size()) != CameraModelNumParams(camera.model)) {
      throw InputError("camera " + std::to_string(id) + ": model " + camera.model +
                       " is not supported by the joint adjustment (pinhole, radial and OpenCV models are)");
    }
  }
  result.rms_before_px = RmsError(*model);

  // Targets first: without a control target seen twice nothing holds the frame.
  std::vector<SurveyTarget> seen = targets;
  for (SurveyTarget& t : seen) t.has_model = false;
  TriangulateTargetsInModel(*model, picks, "", &seen);
  size_t control_seen = 0;
  for (const SurveyTarget& t : seen)
    if (t.has_model && t.role == TargetRole::kControl) ++control_seen;
  if (control_seen == 0) throw InputError("no control target is seen in two of the model's photos: nothing holds the frame");

  // Join the chunks' points where verified matches link them.
  std::map<std::string, uint32_t> image_by_name;
  for (const auto& [id, image] : model->images) image_by_name[image.name] = id;
  std::vector<uint64_t> point_ids;
  std::map<uint64_t, size_t> point_index;
  std::vector<std::vector<uint32_t>> point_images;
  for (const auto& [id, point] : model->points3d) {
    point_index[id] = point_ids.size();
    point_ids.push_back(id);
    std::vector<uint32_t> images;
    for (const ColmapTrackElement& e : point.track) images.push_back(e.image_id);
    std::sort(images.begin(), images.end());
    images.erase(std::unique(images.begin(), images.end()), images.end());
    point_images.push_back(std::move(images));
  }
  Tracks tracks(std::move(point_images));
  const double max_angle = options.max_link_angle_deg * kPi / 180;
  // Every match between two chunks' photos of the model: visit(photo a, photo b, keypoint in a, in b).
  const auto for_each_match = [&](const auto& visit) {
    for (const PairMatches& pair : matches) {
      if (ChunkOfName(pair.image_a) == ChunkOfName(pair.image_b)) continue;
      const auto a = image_by_name.find(pair.image_a), b = image_by_name.find(pair.image_b);
      if (a == image_by_name.end() || b == image_by_name.end()) continue;
      const ColmapImage& ia = model->images.at(a->second);
      const ColmapImage& ib = model->images.at(b->second);
      for (const auto& [k, l] : pair.matches) {
        if (k < ia.point3d_ids.size() && l < ib.point3d_ids.size()) visit(ia, ib, k, l);
      }
    }
  };
  for_each_match([&](const ColmapImage& ia, const ColmapImage& ib, uint32_t k, uint32_t l) {
    const uint64_t pa = ia.point3d_ids[k], pb = ib.point3d_ids[l];
    if (pa == kInvalidPoint3dId || pb == kInvalidPoint3dId) return;
    const size_t ka = point_index.at(pa), kb = point_index.at(pb);
    if (tracks.Find(ka) == tracks.Find(kb)) return;
    const Eigen::Vector3d ca = Centre(ia), cb = Centre(ib);
    const Eigen::Vector3d& xa = model->points3d.at(pa).xyz;
    const Eigen::Vector3d& xb = model->points3d.at(pb).xyz;
    if (Angle(xa - ca, xb - ca) > max_angle || Angle(xa - cb, xb - cb) > max_angle || !tracks.Join(ka, kb)) {
      ++result.links_rejected;
      return;
    }
    ++result.links;
  });
  // Then a point of one chunk whose match in another chunk's photo was not triangulated there gains
  // that observation, where it projects within the same angle of it.
  struct Extension {
    size_t point;
    uint32_t image, keypoint;
  };
  std::vector<Extension> extensions;
  std::set<std::pair<uint32_t, uint32_t>> taken;  // (image, keypoint) given to a point
  const double tan_max_angle = std::tan(max_angle);
  for_each_match([&](const ColmapImage& ia, const ColmapImage& ib, uint32_t k, uint32_t l) {
    const uint64_t pa = ia.point3d_ids[k], pb = ib.point3d_ids[l];
    if ((pa == kInvalidPoint3dId) == (pb == kInvalidPoint3dId)) return;
    const bool from_a = pa != kInvalidPoint3dId;
    const uint64_t point = from_a ? pa : pb;
    const ColmapImage& other = from_a ? ib : ia;
    const uint32_t keypoint = from_a ? l : k;
    if (taken.count({other.image_id, keypoint})) return;
    const ColmapCamera& camera = model->cameras.at(other.camera_id);
    const Eigen::Vector2d uv = ProjectToImage(camera, other, model->points3d.at(point).xyz);
    if (!uv.allFinite() || (uv - other.points2d[keypoint]).norm() > tan_max_angle * camera.params[0] ||
        !tracks.AddImage(point_index.at(point), other.image_id)) {
      ++result.links_rejected;
      return;
    }
    taken.insert({other.image_id, keypoint});
    extensions.push_back({point_index.at(point), other.image_id, keypoint});
  });
  result.extended = extensions.size();

  // The joined model: points in order of their first member, at their members' mean.
  ColmapModel joined;
  joined.cameras = model->cameras;
  joined.images = model->images;
  if (options.one_camera && joined.cameras.size() > 1) {
    // The chunks' copies of one camera become one again, at their mean (weighted by photos).
    const ColmapCamera& first = joined.cameras.begin()->second;
    ColmapCamera one = first;
    one.camera_id = 1;
    std::fill(one.params.begin(), one.params.end(), 0.0);
    for (const auto& [id, camera] : joined.cameras) {
      if (camera.model != first.model || camera.width != first.width || camera.height != first.height) {
        throw InputError("camera " + std::to_string(id) + " (" + camera.model + ", " + std::to_string(camera.width) +
                         " x " + std::to_string(camera.height) + ") is not a copy of camera " +
                         std::to_string(first.camera_id) + ": the photos were not taken with one camera");
      }
    }
    for (auto& [id, image] : joined.images) {
      const std::vector<double>& p = joined.cameras.at(image.camera_id).params;
      for (size_t k = 0; k < p.size(); ++k) one.params[k] += p[k] / static_cast<double>(joined.images.size());
      image.camera_id = 1;
    }
    joined.cameras = {{1, one}};
  }
  std::map<size_t, uint64_t> new_id;  // root -> id
  std::map<uint64_t, size_t> members;
  for (size_t i = 0; i < point_ids.size(); ++i) {
    const size_t root = tracks.Find(i);
    auto [it, fresh] = new_id.emplace(root, joined.points3d.size() + 1);
    const ColmapPoint3d& from = model->points3d.at(point_ids[i]);
    ColmapPoint3d& to = joined.points3d[it->second];
    if (fresh) {
      to = from;
      to.point3d_id = it->second;
    } else {
      to.xyz += from.xyz;
      to.track.insert(to.track.end(), from.track.begin(), from.track.end());
    }
    ++members[it->second];
  }
  for (auto& [id, point] : joined.points3d) {
    point.xyz /= static_cast<double>(members[id]);
    if (members[id] > 1) ++result.joined_points;
  }
  for (auto& [id, image] : joined.images) {
    for (uint64_t& p : image.point3d_ids)
      if (p != kInvalidPoint3dId) p = new_id.at(tracks.Find(point_index.at(p)));
  }
  for (const Extension& e : extensions) {
    const uint64_t id = new_id.at(tracks.Find(e.point));
    joined.points3d.at(id).track.push_back({e.image, e.keypoint});
    joined.images.at(e.image).point3d_ids[e.keypoint] = id;
  }

  // The adjustment.
  ceres::Problem problem;
  std::map<uint32_t, Pose> poses;
  for (const auto& [id, image] : joined.images) {
    const Eigen::Quaterniond q = image.cam_from_world_rotation.normalized();
    Pose& pose = poses[id];
    pose.q[0] = q.w(), pose.q[1] = q.x(), pose.q[2] = q.y(), pose.q[3] = q.z();
    for (int k = 0; k < 3; ++k) pose.t[k] = image.cam_from_world_translation[k];
  }
  std::map<uint32_t, std::vector<double>> intrinsics;  // adjusted copies of the cameras' parameters
  for (const auto& [id, camera] : joined.cameras) intrinsics[id] = camera.params;
  const double sigma = options.reprojection_sigma_px;
  for (auto& [id, point] : joined.points3d) {
    for (const ColmapTrackElement& e : point.track) {
      const ColmapImage& image = joined.images.at(e.image_id);
      const ColmapCamera& camera = joined.cameras.at(image.camera_id);
      if (!ProjectToImage(camera, image, point.xyz).allFinite()) continue;  // behind the camera as tied
      Pose& pose = poses.at(e.image_id);
      problem.AddResidualBlock(MakeReprojection(ProjectionModelOf(camera.model), image.points2d[e.point2d_idx], sigma),
                               new ceres::HuberLoss(kHuberSigmas), pose.q, pose.t, point.xyz.data(),
                               intrinsics.at(image.camera_id).data());
      ++result.observations;
    }
  }
  std::map<std::string, uint32_t> image_by_file;
  for (const auto& [id, image] : joined.images) image_by_file[std::filesystem::path(image.name).filename().string()] = id;
  std::vector<Eigen::Vector3d> target_at(seen.size());
  std::vector<bool> adjusted(seen.size(), false);
  for (size_t t = 0; t < seen.size(); ++t) {
    if (!seen[t].has_model) continue;
    target_at[t] = seen[t].model;
    for (const ImagePick& p : picks) {
      if (p.target != seen[t].name) continue;
      const auto image = image_by_file.find(std::filesystem::path(p.image).filename().string());
      if (image == image_by_file.end()) continue;
      const ColmapImage& view = joined.images.at(image->second);
      const ColmapCamera& camera = joined.cameras.at(view.camera_id);
      if (!ProjectToImage(camera, view, target_at[t]).allFinite()) continue;
      Pose& pose = poses.at(image->second);
      problem.AddResidualBlock(MakeReprojection(ProjectionModelOf(camera.model), p.uv, options.pick_sigma_px), nullptr,
                               pose.q, pose.t, target_at[t].data(), intrinsics.at(view.camera_id).data());
      adjusted[t] = true;
    }
    if (adjusted[t] && seen[t].role == TargetRole::kControl) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<SurveyPrior, 3, 3>(
                                   new SurveyPrior(seen[t].survey, seen[t].accuracy)),
                               nullptr, target_at[t].data());
    }
  }
  for (auto& [id, pose] : poses) {
    if (problem.HasParameterBlock(pose.q)) problem.SetManifold(pose.q, new ceres::QuaternionManifold);
  }
  for (auto& [id, k] : intrinsics) {
    if (!problem.HasParameterBlock(k.data())) continue;
    if (!options.refine_intrinsics) {
      problem.SetParameterBlockConstant(k.data());
      continue;
    }
    // Focal length and distortion, the principal point held (as COLMAP's mapper does).
    const int c = PrincipalPointIndex(ProjectionModelOf(joined.cameras.at(id).model));
    problem.SetManifold(k.data(), new ceres::SubsetManifold(static_cast<int>(k.size()), {c, c + 1}));
  }

  ceres::Solver::Options solver;
  solver.linear_solver_type =
      ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) ? ceres::SPARSE_SCHUR : ceres::DENSE_SCHUR;
  solver.max_num_iterations = options.max_iterations;
  solver.num_threads = 1;  // Ceres's threads sum the reduced system in no fixed order
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  result.iterations = static_cast<int>(summary.iterations.size());
  result.converged = summary.termination_type == ceres::CONVERGENCE;

  for (auto& [id, image] : joined.images) {
    const Pose& pose = poses.at(id);
    image.cam_from_world_rotation = Eigen::Quaterniond(pose.q[0], pose.q[1], pose.q[2], pose.q[3]).normalized();
    image.cam_from_world_translation = Eigen::Vector3d(pose.t[0], pose.t[1], pose.t[2]);
  }
  if (options.refine_intrinsics) {
    for (auto& [id, camera] : joined.cameras) camera.params = intrinsics.at(id);
  }
  for (auto& [id, point] : joined.points3d) point.error = MeanError(joined, point);
  std::vector<Eigen::Vector3d> control, check;
  for (size_t t = 0; t < seen.size(); ++t) {
    if (!adjusted[t]) continue;
    (seen[t].role == TargetRole::kControl ? control : check).push_back(seen[t].survey - target_at[t]);
  }
  result.control = RmseOf(control);
  result.check = RmseOf(check);
  result.rms_after_px = RmsError(joined);
  result.points = joined.points3d.size();
  result.images = joined.images.size();
  result.ran = true;
  *model = std::move(joined);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace candi::photogrammetry

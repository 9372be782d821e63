#include "reconstruction/photogrammetry/sfm/chunked_mapping.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <unordered_map>

#include <Eigen/Eigenvalues>

#include "core/check.h"
#include "core/parallel.h"

namespace candi::photogrammetry {

namespace fs = std::filesystem;

namespace {

constexpr int kMinNeighbours = 5;

std::string FileName(const std::string& name) { return fs::path(name).filename().string(); }


// The camera's focal lengths and principal point, and where its distortion parameters start.
void PinholePart(const ColmapCamera& c, double* fx, double* fy, double* cx, double* cy, size_t* distortion) {
  const std::vector<double>& p = c.params;
  if ((c.model == "SIMPLE_PINHOLE" || c.model == "SIMPLE_RADIAL" || c.model == "RADIAL") && p.size() >= 3) {
    *fx = *fy = p[0], *cx = p[1], *cy = p[2], *distortion = 3;
  } else if ((c.model == "PINHOLE" || c.model == "OPENCV") && p.size() >= 4) {
    *fx = p[0], *fy = p[1], *cx = p[2], *cy = p[3], *distortion = 4;
  } else {
    throw InputError("camera " + std::to_string(c.camera_id) + ": model " + c.model +
                     " is not supported for tying chunks (SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV)");
  }
}

// The distortion COLMAP adds to a normalised point (its models' formulas).
Eigen::Vector2d Distortion(const ColmapCamera& c, size_t from, const Eigen::Vector2d& x) {
  const std::vector<double>& p = c.params;
  const double r2 = x.squaredNorm();
  if (c.model == "SIMPLE_RADIAL") return x * (p[from] * r2);
  if (c.model == "RADIAL") return x * (p[from] * r2 + p[from + 1] * r2 * r2);
  if (c.model == "OPENCV") {
    const double k1 = p[from], k2 = p[from + 1], p1 = p[from + 2], p2 = p[from + 3];
    const double radial = k1 * r2 + k2 * r2 * r2, uv = x.x() * x.y();
    return {x.x() * radial + 2 * p1 * uv + p2 * (r2 + 2 * x.x() * x.x()),
            x.y() * radial + 2 * p2 * uv + p1 * (r2 + 2 * x.y() * x.y())};
  }
  return Eigen::Vector2d::Zero();
}

// The tied chunks' models in the merged frame: one camera a chunk camera, images and points
// renumbered.
ColmapModel Merge(const std::vector<std::pair<ColmapModel, Sim3>>& chunks) {
  ColmapModel merged;
  std::vector<std::pair<std::string, std::pair<size_t, uint32_t>>> names;  // name -> (chunk, old id)
  std::vector<std::map<uint32_t, uint32_t>> camera_ids(chunks.size());
  for (size_t c = 0; c < chunks.size(); ++c) {
    for (const auto& [id, camera] : chunks[c].first.cameras) {
      ColmapCamera copy = camera;
      copy.camera_id = static_cast<uint32_t>(merged.cameras.size() + 1);
      camera_ids[c][id] = copy.camera_id;
      merged.cameras[copy.camera_id] = copy;
    }
    for (const auto& [id, image] : chunks[c].first.images) names.push_back({image.name, {c, id}});
  }
  std::sort(names.begin(), names.end());
  std::vector<std::map<uint32_t, uint32_t>> image_ids(chunks.size());
  for (size_t k = 0; k < names.size(); ++k) {
    const auto [c, old_id] = names[k].second;
    const Sim3& t = chunks[c].second;
    ColmapImage image = chunks[c].first.images.at(old_id);
    image.image_id = static_cast<uint32_t>(k + 1);
    image.camera_id = camera_ids[c].at(image.camera_id);
    // x_cam = R X + t with X = T^-1 Y: R' = R Rs^T, t' = s t - R' ts.
    const Eigen::Quaterniond r = image.cam_from_world_rotation * t.rotation.conjugate();
    image.cam_from_world_translation = t.scale * image.cam_from_world_translation - r * t.translation;
    image.cam_from_world_rotation = r.normalized();
    image_ids[c][old_id] = image.image_id;
    merged.images[image.image_id] = image;
  }
  uint64_t next_point = 1;
  for (size_t c = 0; c < chunks.size(); ++c) {
    std::map<uint64_t, uint64_t> point_ids;
    for (const auto& [id, point] : chunks[c].first.points3d) {
      ColmapPoint3d copy = point;
      copy.point3d_id = next_point++;
      copy.xyz = chunks[c].second * point.xyz;
      for (ColmapTrackElement& e : copy.track) e.image_id = image_ids[c].at(e.image_id);
      point_ids[id] = copy.point3d_id;
      merged.points3d[copy.point3d_id] = copy;
    }
    for (const auto& [old_id, new_id] : image_ids[c]) {
      for (uint64_t& p : merged.images[new_id].point3d_ids) {
        if (p != kInvalidPoint3dId) p = point_ids.at(p);
      }
    }
  }
  return merged;
}

// Distances of `from`'s points to `to`'s local planes (those with >= kMinNeighbours neighbours).
std::vector<double> PlaneDistances(const std::vector<Eigen::Vector3d>& from, const std::vector<Eigen::Vector3d>& to,
                                   double radius) {
  struct KeyHash {
    size_t operator()(const Eigen::Vector3i& k) const {
      return static_cast<size_t>(k.x()) * 73856093u ^ static_cast<size_t>(k.y()) * 19349663u ^
             static_cast<size_t>(k.z()) * 83492791u;
    }
  };
  struct KeyEqual {
    bool operator()(const Eigen::Vector3i& a, const Eigen::Vector3i& b) const { return a == b; }
  };
  const auto key = [&](const Eigen::Vector3d& p) { return (p / radius).array().floor().cast<int>().matrix().eval(); };
  std::unordered_map<Eigen::Vector3i, std::vector<size_t>, KeyHash, KeyEqual> grid;
  for (size_t i = 0; i < to.size(); ++i) grid[key(to[i])].push_back(i);
  std::vector<double> distance(from.size(), -1);
  ParallelFor(size_t{0}, from.size(), [&](size_t i) {
    const Eigen::Vector3i k = key(from[i]);
    std::vector<Eigen::Vector3d> near;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find(k + Eigen::Vector3i(dx, dy, dz));
          if (it == grid.end()) continue;
          for (size_t j : it->second)
            if ((to[j] - from[i]).squaredNorm() <= radius * radius) near.push_back(to[j]);
        }
    if (near.size() < static_cast<size_t>(kMinNeighbours)) return;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& q : near) mean += q;
    mean /= static_cast<double>(near.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3d& q : near) cov += (q - mean) * (q - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    distance[i] = std::abs(eig.eigenvectors().col(0).dot(from[i] - mean));
  });
  std::vector<double> kept;
  for (double d : distance)
    if (d >= 0) kept.push_back(d);
  return kept;
}

double Quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * (v.size() - 1) + 0.5));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

}  // namespace

void ChunkedMappingOptions::Check() const {
  fit.Check();
  joint.Check();
  CANDI_CHECK_OPTION_GE(parallel, 1);
  CANDI_CHECK_OPTION(overlap_radius > 0 && std::isfinite(overlap_radius), overlap_radius, "> 0");
  CANDI_CHECK_OPTION(targets.empty() || !picks.empty(), picks, "a picks file with the targets (the chunks' "
                     "models have their own coordinates: targets are found by their picks)");
}

std::string ChunkOfName(const std::string& name) {
  const size_t slash = name.rfind('/');
  return slash == std::string::npos ? "all" : name.substr(0, slash);
}

std::map<std::string, std::vector<std::string>> ChunksByFolder(const std::vector<std::string>& names) {
  std::map<std::string, std::vector<std::string>> chunks;
  for (const std::string& name : names) chunks[ChunkOfName(name)].push_back(name);
  return chunks;
}

Eigen::Vector2d UndistortPixel(const ColmapCamera& camera, const Eigen::Vector2d& uv) {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  size_t from = 0;
  PinholePart(camera, &fx, &fy, &cx, &cy, &from);
  const Eigen::Vector2d distorted((uv.x() - cx) / fx, (uv.y() - cy) / fy);
  Eigen::Vector2d x = distorted;
  for (int i = 0; i < 50; ++i) x = distorted - Distortion(camera, from, x);  // fixed point
  return {fx * x.x() + cx, fy * x.y() + cy};
}

int TriangulateTargetsInModel(const ColmapModel& model, const std::vector<ImagePick>& picks,
                               const std::string& picks_path, std::vector<SurveyTarget>* targets) {
  // The model's cameras as pinhole projections by file name, and the picks undistorted.
  std::map<std::string, ProjectionMatrix> cameras;
  std::map<std::string, const ColmapCamera*> camera_of;
  for (const auto& [id, image] : model.images) {
    const ColmapCamera& camera = model.cameras.at(image.camera_id);
    double fx = 0, fy = 0, cx = 0, cy = 0;
    size_t from = 0;
    PinholePart(camera, &fx, &fy, &cx, &cy, &from);
    Eigen::Matrix3d k;
    k << fx, 0, cx, 0, fy, cy, 0, 0, 1;
    ProjectionMatrix rt;
    rt << image.cam_from_world_rotation.toRotationMatrix(), image.cam_from_world_translation;
    cameras[FileName(image.name)] = k * rt;
    camera_of[FileName(image.name)] = &camera;
  }
  std::vector<ImagePick> undistorted;
  for (ImagePick p : picks) {
    p.image = FileName(p.image);
    const auto c = camera_of.find(p.image);
    if (c != camera_of.end()) p.uv = UndistortPixel(*c->second, p.uv);
    undistorted.push_back(p);
  }
  return TriangulateTargets(undistorted, picks_path, cameras, targets);
}

ChunkedMappingResult TieChunks(const std::map<std::string, std::string>& chunk_models,
                               const std::map<std::string, std::vector<std::string>>& chunk_images,
                               const std::vector<PairMatches>& matches, const ChunkedMappingOptions& options,
                               const std::string& merged_dir) {
  options.Check();
  const std::vector<SurveyTarget> surveyed = ReadSurveyTargets(options.targets);
  const std::vector<ImagePick> all_picks = ReadImagePicks(options.picks);
  ChunkedMappingResult result;
  std::vector<std::pair<ColmapModel, Sim3>> tied;
  std::vector<std::vector<Eigen::Vector3d>> tied_points;
  std::vector<std::string> tied_names;
  std::string failures;
  bool have_frame = false;
  for (const auto& [name, dir] : chunk_models) {
    ChunkResult chunk;
    chunk.name = name;
    chunk.model_dir = dir;
    const auto images = chunk_images.find(name);
    chunk.images = images == chunk_images.end() ? 0 : images->second.size();
    if (dir.empty()) {
      chunk.reason = chunk.images < 2 ? "a folder of one photo: a chunk is mapped from two or more"
                                      : "its mapper found no model (logs/mapper_" + name + ".log)";
      failures += "\n  " + name + ": " + chunk.reason;
      result.chunks.push_back(chunk);
      continue;
    }
    ColmapModel model = ReadColmapModel(dir);
    chunk.registered = model.images.size();
    chunk.points = model.points3d.size();
    std::vector<SurveyTarget> targets = surveyed;
    TriangulateTargetsInModel(model, all_picks, options.picks, &targets);
    try {
      const GeorefResult g = Georeference(options.fit, targets, options.targets);
      if (have_frame && g.frame != result.frame) throw InputError(options.targets, "", "frames differ between chunks");
      result.frame = g.frame;
      have_frame = true;
      chunk.tied = true;
      chunk.control = g.control;
      chunk.check = g.check;
      chunk.control_used = g.control.count;
      chunk.check_used = g.check.count;
      // local = survey - shift; survey = T model.
      chunk.local_from_model = Sim3(g.survey_from_model.scale, g.survey_from_model.rotation,
                                    g.survey_from_model.translation - g.frame.origin);
    } catch (const InputError& e) {
      chunk.reason = std::string("not tied: ") + e.what();
      failures += "\n  " + name + ": " + chunk.reason;
    }
    for (const SurveyTarget& t : targets) {
      if (t.views > 0 && !t.unused_reason.empty()) chunk.unused_targets.push_back(t.name + ": " + t.unused_reason);
    }
    if (chunk.tied) {
      std::vector<Eigen::Vector3d> points;
      for (const auto& [id, p] : model.points3d) points.push_back(chunk.local_from_model * p.xyz);
      tied_points.push_back(std::move(points));
      tied_names.push_back(name);
      tied.push_back({std::move(model), chunk.local_from_model});
    }
    result.chunks.push_back(chunk);
  }
  if (tied.empty()) {
    throw InputError(options.targets, "", "no chunk could be tied to the targets:" + failures);
  }
  ColmapModel merged = Merge(tied);
  if (options.joint.enabled && tied.size() >= 2) {
    std::vector<SurveyTarget> local = surveyed;
    for (SurveyTarget& t : local) t.survey -= result.frame.origin;
    try {
      result.joint = AdjustJointly(&merged, matches, local, all_picks, options.joint);
    } catch (const InputError& e) {
      result.joint.reason = e.what();
    }
  }
  WriteColmapModelBinary(merged, merged_dir);
  result.merged_dir = merged_dir;
  result.merged_images = merged.images.size();
  result.merged_points = merged.points3d.size();
  for (size_t a = 0; a < tied.size(); ++a) {
    for (size_t b = a + 1; b < tied.size(); ++b) {
      std::vector<double> d = PlaneDistances(tied_points[a], tied_points[b], options.overlap_radius);
      const std::vector<double> back = PlaneDistances(tied_points[b], tied_points[a], options.overlap_radius);
      d.insert(d.end(), back.begin(), back.end());
      if (d.empty()) continue;
      result.pairs.push_back({tied_names[a], tied_names[b], d.size(), Quantile(d, 0.5), Quantile(d, 0.9)});
    }
  }
  return result;
}

}  // namespace candi::photogrammetry

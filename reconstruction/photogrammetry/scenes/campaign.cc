#include "reconstruction/photogrammetry/scenes/campaign.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <regex>
#include <stdexcept>

#include "core/atomic_file.h"
#include "core/check.h"
#include "core/local_frame.h"
#include "core/parallel.h"
#include "core/point_cloud.h"
#include "core/rng.h"
#include "io/image/jpeg_io.h"
#include "io/point_io.h"

namespace candi::photogrammetry {

namespace fs = std::filesystem;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kWallHeight = 2.6;     // each terrace's wall above its walk, metres
constexpr double kGalleryMargin = 1.0;  // the gallery is this much wider than the wall distance
constexpr double kMinHalfSide = 1.5;    // the smallest terrace, metres
constexpr double kPanelBottom = 0.4, kPanelHeight = 0.8, kPanelGap = 0.4, kPanelDepth = 0.04;
// Wall targets above the walk's floor, metres, alternately: never all on one line, so that a
// session whose targets are on one wall still fixes its rotation about that wall.
constexpr double kTargetHeights[2] = {1.35, 2.0};
constexpr int kTargetsPerChunk = 4;     // the third of each session's is a check target
constexpr double kPickNoisePx = 0.3, kSurveyNoiseM = 0.001, kTargetAccuracyM = 0.002;
constexpr double kSurfacePoints = 1.5e6;  // about this many truth points over the campaign

// A side of the square [-a, a]^2 walked anticlockwise seen from above, from the south-west
// corner: side k's outward normal and walking direction.
Eigen::Vector2d SideNormal(int k) {
  static const Eigen::Vector2d n[4] = {{0, -1}, {1, 0}, {0, 1}, {-1, 0}};
  return n[k & 3];
}
Eigen::Vector2d SideAlong(int k) { return SideNormal(k + 1); }

// The walk around the square [-a, a]^2 at distance d: at arclength s (from the south side's west
// end), the camera's position and the inward direction it faces (towards the nearest wall point).
void LoopPose(double a, double d, double s, Eigen::Vector2d* position, Eigen::Vector2d* inward) {
  const double quarter = 2 * a + 0.5 * kPi * d;
  const int k = std::min(3, static_cast<int>(std::floor(s / quarter)));
  const double r = s - k * quarter;
  const Eigen::Vector2d n = SideNormal(k), t = SideAlong(k);
  if (r < 2 * a) {
    *position = (r - a) * t + (a + d) * n;
    *inward = -n;
  } else {  // around the corner, the camera facing its edge
    const double phi = (r - 2 * a) / d;
    const Eigen::Vector2d dir = std::cos(phi) * n + std::sin(phi) * t;
    *position = a * (t + n) + d * dir;
    *inward = -dir;
  }
}

double LoopLength(double a, double d) { return 8 * a + 2 * kPi * d; }

// Splits `total` over weights by largest remainder (ties to the first), each at least `minimum`
// where the total allows it.
std::vector<int> Apportion(int total, const std::vector<double>& weights, int minimum) {
  double sum = 0;
  for (double w : weights) sum += w;
  std::vector<int> count(weights.size());
  std::vector<std::pair<double, size_t>> remainder;
  int used = 0;
  for (size_t i = 0; i < weights.size(); ++i) {
    const double exact = total * weights[i] / sum;
    count[i] = std::max(minimum, static_cast<int>(std::floor(exact)));
    used += count[i];
    remainder.push_back({-(exact - std::floor(exact)), i});
  }
  std::stable_sort(remainder.begin(), remainder.end());
  for (size_t j = 0; used < total; j = (j + 1) % remainder.size(), ++used) ++count[remainder[j].second];
  for (size_t j = remainder.size(); used > total && j-- > 0;) {
    if (count[remainder[j].second] > minimum) --count[remainder[j].second], --used;
  }
  return count;
}

// A point on the walls of sector `sector` (of `sectors`) of the loop around [-a, a]^2 at distance
// d: `fraction` of the way along the straight stretches the sector holds, kept clear of the
// corners (the arcs, where the camera faces an edge, hold no wall). Returns the distance along
// side *side from its start.
double SectorWallPoint(double a, double d, int sector, int sectors, double fraction, int* side) {
  const double quarter = 2 * a + 0.5 * kPi * d, length = LoopLength(a, d);
  const double s0 = length * sector / sectors, s1 = length * (sector + 1) / sectors;
  const double margin = std::min(0.3, 0.2 * a);
  std::vector<std::pair<double, double>> stretches;  // loop arclength intervals on walls
  double total = 0;
  for (int k = 0; k < 4; ++k) {
    const double lo = std::max(s0, k * quarter + margin), hi = std::min(s1, k * quarter + 2 * a - margin);
    if (hi > lo) stretches.push_back({lo, hi}), total += hi - lo;
  }
  if (stretches.empty()) {  // the sector lies on a corner: the wall next to it
    const int k = std::min(3, static_cast<int>(std::floor(0.5 * (s0 + s1) / quarter)));
    *side = k;
    return 2 * a - margin;
  }
  double at = fraction * total;
  for (const auto& [lo, hi] : stretches) {
    if (at <= hi - lo || &stretches.back().first == &lo) {
      const double s = std::min(lo + at, hi);
      *side = std::min(3, static_cast<int>(std::floor(s / quarter)));
      return s - *side * quarter;
    }
    at -= hi - lo;
  }
  return 0;  // not reached
}

SyntheticCarving Panel(int solid, const Eigen::Vector3d& origin, const Eigen::Vector3d& along, double width,
                       uint64_t seed) {
  SyntheticCarving c;
  c.solid = solid;
  c.origin = origin;
  c.u_axis = along;
  c.v_axis = Eigen::Vector3d::UnitZ();
  c.width = width;
  c.height = kPanelHeight;
  c.depth = kPanelDepth;
  c.seed = seed;
  return c;
}

std::string Fixed(double v, int decimals) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, v);
  return text;
}

}  // namespace

void CampaignOptions::Check() const {
  CANDI_CHECK_OPTION_IN(photos, 8, 5000);
  CANDI_CHECK_OPTION_IN(width, 64, 8192);
  CANDI_CHECK_OPTION_IN(chunks, 1, 64);
  CANDI_CHECK_OPTION(uav_photos >= 0 && uav_photos <= photos - 4 * chunks, uav_photos,
                     "in [0, photos - 4 * chunks] (each session keeps at least 4 photos)");
  CANDI_CHECK_OPTION_IN(heights, 1, 4);
  CANDI_CHECK_OPTION(wall_distance >= 0.5 && wall_distance <= 10, wall_distance, "in [0.5, 10]");
  CANDI_CHECK_OPTION(overlap >= 0.2 && overlap <= 0.9, overlap, "in [0.2, 0.9]");
  CANDI_CHECK_OPTION(fov_degrees > 20 && fov_degrees < 120, fov_degrees, "in (20, 120)");
  CANDI_CHECK_OPTION_GT(focal_mm, 0);
  CANDI_CHECK_OPTION(gps_sigma >= 0 && std::isfinite(gps_sigma), gps_sigma, ">= 0");
  CANDI_CHECK_OPTION(noise_sigma >= 0 && std::isfinite(noise_sigma), noise_sigma, ">= 0");
  CANDI_CHECK_OPTION_IN(supersample, 1, 8);
  CANDI_CHECK_OPTION_IN(jpeg_quality, 50, 100);
}

Campaign PlanCampaign(const CampaignOptions& options) {
  options.Check();
  Campaign c;
  c.options = options;
  c.wall_height = kWallHeight;
  const double d = options.wall_distance, g = d + kGalleryMargin;
  const int height_px = options.width * 3 / 4;
  const double half_fov = 0.5 * options.fov_degrees * kPi / 180;
  const double step = 2 * d * std::tan(half_fov) * (1 - options.overlap);
  const int walk_photos = options.photos - options.uav_photos;
  // The terraces: as many as keep the top one at least a third of the lowest (and >= 1.5 m), with
  // the loops' total length what the walk photos cover at this step.
  const double per_row = walk_photos * step / options.heights;
  int terraces = 1;
  double a0 = std::max(kMinHalfSide, (per_row - 2 * kPi * d) / 8);
  for (int t = 2; t <= 5; ++t) {
    const double a = (per_row + 4 * g * t * (t - 1) - 2 * kPi * d * t) / (8 * t);
    if (a - (t - 1) * g < std::max(kMinHalfSide, a / 3)) break;
    terraces = t, a0 = a;
  }
  for (int j = 0; j < terraces; ++j) {
    c.terrace_half_sides.push_back(a0 - j * g);
    c.terrace_floors.push_back(j * kWallHeight);
  }
  // The scene: the ground, the terraces (each a box from the ground up), panels on every wall.
  const Eigen::Vector3d stone(0.80, 0.74, 0.62), soil(0.62, 0.56, 0.45);
  const double ground = a0 + d + 60;
  c.scene.solids.push_back(SyntheticBox({-ground, -ground, -1}, {ground, ground, 0}, soil));
  c.scene.light = Eigen::Vector3d(0.45, -0.6, 0.66).normalized();
  c.scene.block_size = 0.45;
  c.scene.ambient = 0.6;  // a bright sky: the walls away from the sun keep their texture
  Rng rng(options.seed ^ 0xca3a1e5ull);
  for (int j = 0; j < terraces; ++j) {
    const double a = c.terrace_half_sides[j], z = c.terrace_floors[j];
    const int solid = static_cast<int>(c.scene.solids.size());
    c.scene.solids.push_back(SyntheticBox({-a, -a, 0}, {a, a, z + kWallHeight}, stone));
    const double width = std::min(1.6, 2 * a - 0.6);
    const int panels = std::max(1, static_cast<int>(std::floor((2 * a - 0.2) / (width + kPanelGap))));
    const double span = panels * width + (panels - 1) * kPanelGap;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d n = SideNormal(k), t = SideAlong(k);
      for (int p = 0; p < panels; ++p) {
        const Eigen::Vector2d at = a * n + (-0.5 * span + p * (width + kPanelGap)) * t;
        c.scene.carvings.push_back(Panel(solid, {at.x(), at.y(), z + kPanelBottom}, {t.x(), t.y(), 0}, width,
                                         rng.Next()));
      }
    }
  }
  // The loops (terrace, row), their photo counts, and the sessions as sectors of each loop.
  struct Loop {
    int terrace, row;
    double length, z;
  };
  std::vector<Loop> loops;
  std::vector<double> weights;
  for (int j = 0; j < terraces; ++j) {
    for (int r = 0; r < options.heights; ++r) {
      const double z = c.terrace_floors[j] + 1.5 + 0.6 * (r - 0.5 * (options.heights - 1));
      loops.push_back({j, r, LoopLength(c.terrace_half_sides[j], d), z});
      weights.push_back(loops.back().length);
    }
  }
  const std::vector<int> counts = Apportion(walk_photos, weights, 4);
  for (int s = 0; s < options.chunks; ++s) c.chunks.push_back("s" + std::to_string(s + 1));
  std::vector<std::vector<CampaignPhoto>> sessions(options.chunks);
  for (size_t l = 0; l < loops.size(); ++l) {
    const double a = c.terrace_half_sides[loops[l].terrace];
    for (int i = 0; i < counts[l]; ++i) {
      CampaignPhoto photo;
      photo.terrace = loops[l].terrace;
      photo.row = loops[l].row;
      photo.walk = static_cast<double>(i) / counts[l];
      const int session = std::min(options.chunks - 1, static_cast<int>(photo.walk * options.chunks));
      photo.chunk = c.chunks[session];
      Eigen::Vector2d p, in;
      LoopPose(a, d, photo.walk * loops[l].length, &p, &in);
      const Eigen::Vector3d eye(p.x(), p.y(), loops[l].z);
      photo.camera = LookAtCamera(eye, eye + Eigen::Vector3d(in.x(), in.y(), 0), options.width, height_px,
                                  options.fov_degrees);
      sessions[session].push_back(photo);
    }
  }
  // The UAV ring: its own session, looking down at the building's middle from 40 degrees.
  const double top = terraces * kWallHeight;
  const double uav_distance = std::max(8.0, 2.6 * (a0 + d) + top);
  if (options.uav_photos > 0) {
    c.chunks.push_back("uav");
    sessions.emplace_back();
    const Eigen::Vector3d look(0, 0, 0.4 * top);
    for (int i = 0; i < options.uav_photos; ++i) {
      CampaignPhoto photo;
      photo.chunk = "uav";
      photo.walk = static_cast<double>(i) / options.uav_photos;
      const double az = -0.5 * kPi + 2 * kPi * photo.walk, el = 40 * kPi / 180;
      const Eigen::Vector3d eye =
          look + uav_distance * Eigen::Vector3d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      photo.camera = LookAtCamera(eye, look, options.width, height_px, options.fov_degrees);
      sessions.back().push_back(photo);
    }
  }
  for (size_t s = 0; s < sessions.size(); ++s) {
    for (size_t i = 0; i < sessions[s].size(); ++i) {
      char name[64];
      std::snprintf(name, sizeof(name), "%s_%04zu.jpg", c.chunks[s].c_str(), i + 1);
      sessions[s][i].name = name;
      c.photos.push_back(sessions[s][i]);
    }
  }
  // Targets: four a session on the walls above the panels, spread over its sector and terraces
  // (on a straight stretch, clear of the corners); four on the ground for the UAV ring.
  int number = 0;
  for (int s = 0; s < options.chunks; ++s) {
    for (int i = 0; i < kTargetsPerChunk; ++i) {
      const int j = i % terraces;
      const double a = c.terrace_half_sides[j];
      int side = 0;
      const double r = SectorWallPoint(a, d, s, options.chunks, (i + 0.5) / kTargetsPerChunk, &side);
      const Eigen::Vector2d n = SideNormal(side), t = SideAlong(side);
      const Eigen::Vector2d on_wall = (r - a) * t + a * n;
      char name[16];
      std::snprintf(name, sizeof(name), "T%02d", ++number);
      CampaignTarget target;
      target.name = name;
      target.chunk = c.chunks[s];
      target.center = {on_wall.x(), on_wall.y(), c.terrace_floors[j] + kTargetHeights[i % 2]};
      target.normal = {n.x(), n.y(), 0};
      target.radius = std::clamp(0.04 * d, 0.05, 0.3);
      target.check = i == 2;
      c.targets.push_back(target);
    }
  }
  if (options.uav_photos > 0) {
    const double gsd = 2 * uav_distance * std::tan(half_fov) / options.width;  // metres a pixel, roughly
    const double r = a0 + d + 1.5;
    const Eigen::Vector2d corners[4] = {{-r, -r}, {r, -r}, {r, r}, {-r, r}};
    for (int i = 0; i < 4; ++i) {
      CampaignTarget target;
      target.name = "G" + std::to_string(i + 1);
      target.chunk = "uav";
      target.center = {corners[i].x(), corners[i].y(), 0};
      target.normal = Eigen::Vector3d::UnitZ();
      target.radius = std::max(0.15, 10 * gsd);
      target.check = i == 2;
      c.targets.push_back(target);
    }
  }
  for (const CampaignTarget& t : c.targets) c.scene.markers.push_back({t.name, t.center, t.radius});
  return c;
}

SyntheticViewsOptions CampaignRenderOptions(const CampaignOptions& options) {
  SyntheticViewsOptions render;
  render.texture_cell = 0.03;
  render.supersample = options.supersample;
  render.noise_sigma = options.noise_sigma;
  render.seed = options.seed;
  return render;
}

std::vector<SyntheticView> RenderCampaignViews(const Campaign& campaign) {
  const SyntheticViewsOptions render = CampaignRenderOptions(campaign.options);
  std::vector<SyntheticView> views(campaign.photos.size());
  ParallelFor(size_t{0}, views.size(), [&](size_t i) {
    views[i] = RenderSyntheticView(campaign.scene, campaign.photos[i].camera, render, static_cast<int>(i));
    views[i].name = fs::path(campaign.photos[i].name).replace_extension(".png").string();
  });
  return views;
}

Campaign WriteCampaign(const CampaignOptions& options, const std::string& output_dir, bool overwrite,
                       const ProgressCallback& progress) {
  const Campaign c = PlanCampaign(options);
  const fs::path out = fs::absolute(output_dir).lexically_normal();
  std::error_code ec;
  if (fs::exists(out / "campaign.json") && !overwrite) {
    throw InputError(output_dir, "", "holds a campaign already (campaign.json); pass --overwrite to replace it");
  }
  // Replacing: the sessions the earlier campaign.json lists go first (no other folder is touched).
  if (fs::exists(out / "campaign.json")) {
    const std::string old = ReadFileToString((out / "campaign.json").string());
    static const std::regex kSession(R"re(\{"name": "([a-z0-9]+)", "photos")re");
    for (std::sregex_iterator it(old.begin(), old.end(), kSession), end; it != end; ++it) {
      fs::remove_all(out / (*it)[1].str(), ec);
    }
  }
  fs::create_directories(out / "truth", ec);
  if (ec) throw InputError(output_dir, "", "cannot create the folder: " + ec.message());
  for (const std::string& chunk : c.chunks) {
    fs::remove_all(out / chunk, ec);
    fs::create_directories(out / chunk, ec);
    if (ec) throw InputError((out / chunk).string(), "", "cannot create the folder: " + ec.message());
  }
  // The photos, rendered and written as they are done; the truth surface a sample of each one's
  // true depth.
  const SyntheticViewsOptions render = CampaignRenderOptions(options);
  io::JpegExif exif;
  exif.focal_mm = options.focal_mm;
  const PinholeCamera& first = c.photos.front().camera;
  exif.sensor_width_mm = options.focal_mm * first.width / first.fx;
  const double pixels = static_cast<double>(first.width) * first.height * c.photos.size();
  const int stride = std::max(3, static_cast<int>(std::ceil(std::sqrt(pixels / kSurfacePoints))));
  std::vector<std::vector<Eigen::Vector3d>> surface(c.photos.size());
  std::atomic<uint64_t> done{0};
  std::mutex progress_mutex;
  ParallelFor(size_t{0}, c.photos.size(), [&](size_t i) {
    const CampaignPhoto& photo = c.photos[i];
    const SyntheticView view = RenderSyntheticView(c.scene, photo.camera, render, static_cast<int>(i));
    WriteFileAtomic((out / photo.chunk / photo.name).string(),
                    io::EncodeJpegWithExif(view.image, exif, options.jpeg_quality));
    for (int y = stride / 2; y < view.depth.height(); y += stride) {
      for (int x = stride / 2; x < view.depth.width(); x += stride) {
        const double z = view.depth.at(x, y);
        if (z > 0) surface[i].push_back(view.camera.ToWorld(z * view.camera.Ray(x + 0.5, y + 0.5)));
      }
    }
    const uint64_t n = ++done;
    if (progress) {
      std::lock_guard<std::mutex> lock(progress_mutex);
      progress(n, c.photos.size());
    }
  });
  // The survey: targets with 1 mm noise, their picks in the photos with 0.3 px, the priors.
  Rng rng(options.seed ^ 0x5a17e7ull);
  std::string targets = "name,E,N,H,role,accuracy\n", picks = "name,image,u,v\n";
  for (const CampaignTarget& t : c.targets) {
    const Eigen::Vector3d e = c.ToSurvey(t.center) + kSurveyNoiseM * Eigen::Vector3d(rng.Normal(), rng.Normal(), rng.Normal());
    targets += t.name + "," + Fixed(e.x(), 4) + "," + Fixed(e.y(), 4) + "," + Fixed(e.z(), 4) + "," +
               (t.check ? "check" : "control") + "," + Fixed(kTargetAccuracyM, 3) + "\n";
  }
  for (const CampaignPhoto& photo : c.photos) {
    const PinholeCamera& cam = photo.camera;
    for (const CampaignTarget& t : c.targets) {
      if (!c.scene.Sees(cam, t.center)) continue;
      const Eigen::Vector2d uv = cam.Project(cam.ToCamera(t.center));
      const double margin = 8;
      if (uv.x() < margin || uv.y() < margin || uv.x() > cam.width - margin || uv.y() > cam.height - margin) continue;
      // Seen at a slant of more than 70 degrees, a target cannot be picked.
      if ((cam.Center() - t.center).normalized().dot(t.normal) < std::cos(70 * kPi / 180)) continue;
      picks += t.name + "," + photo.name + "," + Fixed(uv.x() + kPickNoisePx * rng.Normal(), 2) + "," +
               Fixed(uv.y() + kPickNoisePx * rng.Normal(), 2) + "\n";
    }
  }
  WriteFileAtomic((out / "targets.csv").string(), targets);
  WriteFileAtomic((out / "picks.csv").string(), picks);
  if (options.gps_sigma > 0) {
    std::string priors = "name,E,N,H,sigma\n";
    for (const CampaignPhoto& photo : c.photos) {
      const Eigen::Vector3d e =
          c.ToSurvey(photo.camera.Center()) + options.gps_sigma * Eigen::Vector3d(rng.Normal(), rng.Normal(), rng.Normal());
      priors += photo.name + "," + Fixed(e.x(), 3) + "," + Fixed(e.y(), 3) + "," + Fixed(e.z(), 3) + "," +
                Fixed(options.gps_sigma, 3) + "\n";
    }
    WriteFileAtomic((out / "priors.csv").string(), priors);
  } else {
    fs::remove(out / "priors.csv", ec);
  }
  // The truth: cameras (survey frame; COLMAP's cam_from_world rotation as a quaternion) and the
  // surface sample.
  std::string cameras = "name,chunk,terrace,row,E,N,H,qw,qx,qy,qz,fx,fy,cx,cy,width,height\n";
  for (const CampaignPhoto& photo : c.photos) {
    const PinholeCamera& cam = photo.camera;
    const Eigen::Vector3d e = c.ToSurvey(cam.Center());
    const Eigen::Quaterniond q(cam.rotation);
    cameras += photo.name + "," + photo.chunk + "," + std::to_string(photo.terrace) + "," + std::to_string(photo.row) +
               "," + Fixed(e.x(), 6) + "," + Fixed(e.y(), 6) + "," + Fixed(e.z(), 6) + "," + Fixed(q.w(), 12) + "," +
               Fixed(q.x(), 12) + "," + Fixed(q.y(), 12) + "," + Fixed(q.z(), 12) + "," + Fixed(cam.fx, 6) + "," +
               Fixed(cam.fy, 6) + "," + Fixed(cam.cx, 6) + "," + Fixed(cam.cy, 6) + "," + std::to_string(cam.width) +
               "," + std::to_string(cam.height) + "\n";
  }
  WriteFileAtomic((out / "truth" / "cameras.csv").string(), cameras);
  PointCloud cloud;
  cloud.frame.origin = kCampaignSurveyOrigin;
  for (const auto& points : surface) cloud.positions.insert(cloud.positions.end(), points.begin(), points.end());
  io::WritePointCloud((out / "truth" / "surface.ply").string(), cloud);
  // campaign.json: what was made, for people and for `candi bench campaign`.
  std::string json = "{\n  \"photos\": " + std::to_string(c.photos.size()) + ",\n  \"width\": " +
                     std::to_string(options.width) + ",\n  \"height\": " + std::to_string(first.height) +
                     ",\n  \"seed\": " + std::to_string(options.seed) + ",\n  \"wall_distance\": " +
                     Fixed(options.wall_distance, 3) + ",\n  \"overlap\": " + Fixed(options.overlap, 3) +
                     ",\n  \"focal_px\": " + Fixed(first.fx, 6) + ",\n  \"survey_origin\": [" +
                     Fixed(kCampaignSurveyOrigin.x(), 3) + ", " + Fixed(kCampaignSurveyOrigin.y(), 3) + ", " +
                     Fixed(kCampaignSurveyOrigin.z(), 3) + "],\n  \"terraces\": [";
  for (size_t j = 0; j < c.terrace_half_sides.size(); ++j) {
    json += std::string(j ? ", " : "") + "{\"half_side\": " + Fixed(c.terrace_half_sides[j], 4) +
            ", \"floor\": " + Fixed(c.terrace_floors[j], 3) + "}";
  }
  json += "],\n  \"carvings\": " + std::to_string(c.scene.carvings.size()) + ",\n  \"chunks\": [";
  for (size_t s = 0; s < c.chunks.size(); ++s) {
    int photos = 0, control = 0, check = 0;
    for (const CampaignPhoto& p : c.photos) photos += p.chunk == c.chunks[s];
    for (const CampaignTarget& t : c.targets) {
      if (t.chunk == c.chunks[s]) ++(t.check ? check : control);
    }
    json += std::string(s ? ", " : "") + "{\"name\": \"" + c.chunks[s] + "\", \"photos\": " + std::to_string(photos) +
            ", \"control\": " + std::to_string(control) + ", \"check\": " + std::to_string(check) + "}";
  }
  json += "],\n  \"surface_points\": " + std::to_string(cloud.size()) + "\n}\n";
  WriteFileAtomic((out / "campaign.json").string(), json);
  return c;
}

}  // namespace candi::photogrammetry

#include "reconstruction/relief/relief_photo_pairs.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "core/check.h"
#include "core/text_format.h"
#include "io/image/png_io.h"
#include "reconstruction/relief/relief_dataset.h"
#include "reconstruction/relief/relief_image.h"

namespace candi::relief {

namespace {

constexpr float kNoDepth = std::numeric_limits<float>::infinity();

std::string Stem(const std::string& image_name) {
  return std::filesystem::path(image_name).stem().string();
}

double TextNumber(const io::PngText& text, const char* key) {
  const auto it = text.find(key);
  if (it == text.end()) return 0;
  try {
    return std::stod(it->second);
  } catch (const std::exception&) {
    return 0;
  }
}

}  // namespace

SceneRegion ParseSceneRegion(const std::string& text) {
  const auto fail = [&](const std::string& why) -> SceneRegion {
    throw std::invalid_argument("region '" + text + "': " + why +
                                " (box:x0,y0,z0,x1,y1,z1 or side:nx,ny,nz,offset, in the cloud's frame)");
  };
  const size_t colon = text.find(':');
  if (colon == std::string::npos) return fail("no kind");
  const std::string kind = text.substr(0, colon);
  const std::vector<double> v = ParseNumbers(text.substr(colon + 1), ',', "region '" + text + "'");
  SceneRegion r;
  if (kind == "box") {
    if (v.size() != 6) return fail("a box takes 6 numbers");
    r.kind = SceneRegion::Kind::kBox;
    r.lo = Eigen::Vector3d(v[0], v[1], v[2]).cwiseMin(Eigen::Vector3d(v[3], v[4], v[5]));
    r.hi = Eigen::Vector3d(v[0], v[1], v[2]).cwiseMax(Eigen::Vector3d(v[3], v[4], v[5]));
    if (!((r.hi - r.lo).array() > 0).all()) return fail("the box is empty");
  } else if (kind == "side") {
    if (v.size() != 4) return fail("a side takes 4 numbers");
    r.kind = SceneRegion::Kind::kSide;
    r.normal = Eigen::Vector3d(v[0], v[1], v[2]);
    if (!(r.normal.norm() > 0)) return fail("the normal is zero");
    r.offset = v[3];
  } else {
    return fail("unknown kind '" + kind + "'");
  }
  return r;
}

void PhotoPairOptions::Check() const {
  CANDI_CHECK_OPTION_IN(max_side, 32, 16384);
  CANDI_CHECK_OPTION_IN(occlusion_radius, 0, 16);
  CANDI_CHECK_OPTION_IN(occlusion_tolerance, 0, 1);
  CANDI_CHECK_OPTION(near_percentile >= 0 && near_percentile < 1, near_percentile, "in [0, 1)");
  CANDI_CHECK_OPTION(far_percentile > near_percentile && far_percentile <= 1, far_percentile,
                     "in (near_percentile, 1]");
}

double LevelOfCameraDepth(double z, double near, double far) {
  if (!(far > near)) return 128;
  const double level = kMinValidLevel + (kMaxLevel - kMinValidLevel) * (z - near) / (far - near);
  return std::clamp(level, kMinValidLevel, kMaxLevel);
}

double CameraDepthOfLevel(double level, double near, double far) {
  return near + (level - kMinValidLevel) * (far - near) / (kMaxLevel - kMinValidLevel);
}

PhotoPair BuildPhotoPair(const PhotoPairOptions& options, const photogrammetry::ColmapCamera& camera,
                         const photogrammetry::ColmapImage& image, const ImageF& photo,
                         const std::string& photo_path, const std::vector<Eigen::Vector3d>& points,
                         const std::vector<uint8_t>* in_region) {
  options.Check();
  CANDI_CHECK(in_region == nullptr || in_region->size() == points.size());
  CANDI_CHECK(camera.width > 0 && camera.height > 0) << "camera " << camera.camera_id << " has no size";
  if (photo.empty()) throw InputError(photo_path, "", "photo has no pixels");
  const double aspect_photo = static_cast<double>(photo.width()) / photo.height();
  const double aspect_camera = static_cast<double>(camera.width) / camera.height;
  if (std::abs(aspect_photo / aspect_camera - 1) > 0.01) {
    throw InputError(photo_path, "", "photo is " + std::to_string(photo.width()) + "x" +
                                         std::to_string(photo.height()) + ", its camera " +
                                         std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                                         ": not the same aspect ratio");
  }
  const double s = std::min(1.0, static_cast<double>(options.max_side) / std::max(camera.width, camera.height));
  const int w = std::max(1, static_cast<int>(std::lround(camera.width * s)));
  const int h = std::max(1, static_cast<int>(std::lround(camera.height * s)));
  const double sx = static_cast<double>(w) / camera.width, sy = static_cast<double>(h) / camera.height;

  // z-buffer of the nearest point per pixel.
  std::vector<float> z(static_cast<size_t>(w) * h, kNoDepth);
  std::vector<uint8_t> nearest_in_region(in_region ? z.size() : 0, 0);
  const Eigen::Matrix3d r = image.cam_from_world_rotation.normalized().toRotationMatrix();
  for (size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& p = points[i];
    if (!p.allFinite()) continue;
    const double depth = (r * p + image.cam_from_world_translation).z();
    if (!(depth > 0)) continue;
    const Eigen::Vector2d uv = photogrammetry::ProjectToImage(camera, image, p);
    if (!uv.allFinite()) continue;
    const double px = std::floor(uv.x() * sx), py = std::floor(uv.y() * sy);
    if (px < 0 || py < 0 || px >= w || py >= h) continue;
    const size_t at = static_cast<size_t>(py) * w + static_cast<size_t>(px);
    if (static_cast<float>(depth) < z[at]) {
      z[at] = static_cast<float>(depth);
      if (in_region) nearest_in_region[at] = (*in_region)[i] ? 255 : 0;
    }
  }

  // Points hidden by a nearer neighbour: the surface behind showing through a sparse spot.
  std::vector<float> visible = z;
  const int rad = options.occlusion_radius;
  if (rad > 0) {
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const float d = z[static_cast<size_t>(y) * w + x];
        if (d == kNoDepth) continue;
        const double limit = d * (1 - options.occlusion_tolerance);
        bool hidden = false;
        for (int v = std::max(0, y - rad); v <= std::min(h - 1, y + rad) && !hidden; ++v) {
          for (int u = std::max(0, x - rad); u <= std::min(w - 1, x + rad); ++u) {
            if (z[static_cast<size_t>(v) * w + u] < limit) {
              hidden = true;
              break;
            }
          }
        }
        if (hidden) visible[static_cast<size_t>(y) * w + x] = kNoDepth;
      }
    }
  }

  PhotoPair pair;
  pair.name = Stem(image.name);
  pair.photo = Resample(photo, w, h);
  pair.depth = ImageF(w, h, 1, 0.0f);
  pair.mask = Image8(w, h, 1, 0);
  if (in_region) {
    pair.region = Image8(w, h, 1, 0);
    std::copy(nearest_in_region.begin(), nearest_in_region.end(), pair.region.values().begin());
  }
  std::vector<float> known;
  for (float d : visible) {
    if (d != kNoDepth) known.push_back(d);
  }
  if (known.empty()) return pair;
  pair.near = PercentileOf(known, options.near_percentile);
  pair.far = PercentileOf(std::move(known), options.far_percentile);
  if (!(pair.far - pair.near > 1e-9 * std::abs(pair.far))) pair.far = pair.near;  // flat: level 128
  for (size_t i = 0; i < visible.size(); ++i) {
    if (visible[i] == kNoDepth) continue;
    pair.depth.values()[i] = static_cast<float>(LevelOfCameraDepth(visible[i], pair.near, pair.far));
    pair.mask.values()[i] = 255;
  }
  return pair;
}

void WritePhotoPair(const std::string& dir, const PhotoPair& pair) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError(dir, "", "cannot create the folder: " + ec.message());
  const std::string base = dir + "/" + pair.name;
  const io::PngText text = {{"candi_depth_near", FormatDouble(pair.near)},
                        {"candi_depth_far", FormatDouble(pair.far)}};
  WritePhoto(base + "_photo.png", pair.photo);
  WriteDepth16(base + "_depth.png", pair.depth, text);
  io::WritePng(base + "_mask.png", pair.mask);
}

std::vector<PhotoPair> ReadPhotoPairs(const std::string& dir) {
  std::vector<PhotoPair> pairs;
  for (const std::string& photo : PairPhotoPaths(dir)) {
    const std::string base = photo.substr(0, photo.size() - 10);
    PhotoPair p;
    p.name = std::filesystem::path(base).filename().string();
    p.photo = ReadPhoto(photo);
    io::PngText text;
    p.depth = ReadDepth(base + "_depth.png", &text);
    p.near = TextNumber(text, "candi_depth_near");
    p.far = TextNumber(text, "candi_depth_far");
    auto same_size = [&](int width, int height, const std::string& path) {
      if (width != p.photo.width() || height != p.photo.height()) {
        throw InputError(path, "", std::to_string(width) + "x" + std::to_string(height) +
                                       ", its photo " + photo + " is " + std::to_string(p.photo.width()) +
                                       "x" + std::to_string(p.photo.height()));
      }
    };
    same_size(p.depth.width(), p.depth.height(), base + "_depth.png");
    std::error_code ec;
    if (std::filesystem::exists(base + "_mask.png", ec)) {
      const io::PngImage mask = io::ReadPng(base + "_mask.png");
      if (mask.bit_depth != 8 || mask.image8.channels() != 1) {
        throw InputError(base + "_mask.png", "", "a mask must be an 8-bit grey PNG");
      }
      same_size(mask.image8.width(), mask.image8.height(), base + "_mask.png");
      p.mask = mask.image8;
    }
    pairs.push_back(std::move(p));
  }
  if (pairs.empty()) throw InputError(dir, "", "holds no <name>_photo.png + <name>_depth.png pairs");
  return pairs;
}

}  // namespace candi::relief

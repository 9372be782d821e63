#include "reconstruction/relief/relief_dataset.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <stdexcept>

#include "core/check.h"
#include "core/rng.h"
#include "reconstruction/relief/relief_image.h"

namespace candi::relief {

namespace {

// Rows of panel_from_cloud (x along the wall, y up, z out) and the mean.
Eigen::Matrix3d PanelAxes(const ScanRasterOptions& o, const PointCloud& cloud, Eigen::Vector3d* mean) {
  *mean = Eigen::Vector3d::Zero();
  for (const auto& p : cloud.positions) *mean += p;
  *mean /= static_cast<double>(cloud.size());
  if (o.frame == "panel") return Eigen::Matrix3d::Identity();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : cloud.positions) cov += (p - *mean) * (p - *mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);  // ascending eigenvalues
  Eigen::Vector3d x = eig.eigenvectors().col(2), z = eig.eigenvectors().col(0);
  // z points away from the wall: the side with the longer, sparser tail (positive skew is the
  // carving standing out of a dense wall plane).
  double m3 = 0;
  for (const auto& p : cloud.positions) m3 += std::pow((p - *mean).dot(z), 3);
  if (m3 < 0) z = -z;
  // Orientation: y up in a z-up world when the panel stands; else x along its largest component.
  Eigen::Vector3d y = z.cross(x);
  Eigen::Index largest = 0;
  x.cwiseAbs().maxCoeff(&largest);
  if (std::abs(y.z()) > 0.3 ? y.z() < 0 : x[largest] < 0) x = -x, y = -y;
  Eigen::Matrix3d r;
  r.row(0) = x.transpose();
  r.row(1) = y.transpose();
  r.row(2) = z.transpose();
  return r;
}

// Fills "no data" (NaN) pixels within `passes` pixels of data with the mean of their neighbours.
void FillHoles(ImageF* h, ImageF* grey, int passes) {
  for (int pass = 0; pass < passes; ++pass) {
    ImageF nh = *h, ng = *grey;
    for (int y = 0; y < h->height(); ++y) {
      for (int x = 0; x < h->width(); ++x) {
        if (!std::isnan(h->at(x, y))) continue;
        double sh = 0, sg = 0;
        int n = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const int xx = x + dx, yy = y + dy;
            if (xx < 0 || yy < 0 || xx >= h->width() || yy >= h->height() || std::isnan(h->at(xx, yy))) continue;
            sh += h->at(xx, yy), sg += grey->at(xx, yy), ++n;
          }
        }
        if (n > 0) nh.at(x, y) = static_cast<float>(sh / n), ng.at(x, y) = static_cast<float>(sg / n);
      }
    }
    *h = std::move(nh), *grey = std::move(ng);
  }
}

float Bilinear(const ImageF& im, double x, double y, float outside) {
  if (x < -0.5 || y < -0.5 || x > im.width() - 0.5 || y > im.height() - 0.5) return outside;
  x = std::clamp(x, 0.0, im.width() - 1.0), y = std::clamp(y, 0.0, im.height() - 1.0);
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const int x1 = std::min(x0 + 1, im.width() - 1), y1 = std::min(y0 + 1, im.height() - 1);
  const double fx = x - x0, fy = y - y0;
  return static_cast<float>((1 - fy) * ((1 - fx) * im.at(x0, y0) + fx * im.at(x1, y0)) +
                            fy * ((1 - fx) * im.at(x0, y1) + fx * im.at(x1, y1)));
}

std::string PairName(const std::string& dir, size_t i, const char* kind) {
  char name[64];
  std::snprintf(name, sizeof(name), "/%06zu_%s.png", i, kind);
  return dir + name;
}

}  // namespace

float PercentileOf(std::vector<float> v, double q) {
  if (v.empty()) return 0;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * v.size()));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

void ScanRasterOptions::Check() const {
  CANDI_CHECK_OPTION(pixels_per_m > 0 && std::isfinite(pixels_per_m), pixels_per_m, "> 0");
  CANDI_CHECK_OPTION(frame == "auto" || frame == "panel", frame, "auto or panel");
  CANDI_CHECK_OPTION(depth_m > 0 && std::isfinite(depth_m), depth_m, "> 0");
  CANDI_CHECK_OPTION_IN(fill_holes, 0, 64);
  photo.Check();
}

void PatchOptions::Check() const {
  CANDI_CHECK_OPTION(patch >= 32 && patch % 32 == 0, patch, "a multiple of 32, >= 32");
  CANDI_CHECK_OPTION_GE(stride, 1);
  CANDI_CHECK_OPTION_IN(min_valid_fraction, 0, 1);
}

void AugmentOptions::Check() const {
  CANDI_CHECK_OPTION_IN(rotate_probability, 0, 1);
  CANDI_CHECK_OPTION_IN(flip_probability, 0, 1);
  CANDI_CHECK_OPTION_IN(brightness_probability, 0, 1);
  CANDI_CHECK_OPTION_IN(max_rotation_deg, 0, 45);
}

TrainingPair RasterizeScan(const ScanRasterOptions& o, const PointCloud& cloud,
                           const std::string& path) {
  o.Check();
  if (cloud.size() < 3) throw InputError(path, "", "a scan needs at least 3 points");
  Eigen::Vector3d mean;
  const Eigen::Matrix3d r = PanelAxes(o, cloud, &mean);
  std::vector<Eigen::Vector3d> q(cloud.size());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (size_t i = 0; i < cloud.size(); ++i) {
    q[i] = r * (cloud.positions[i] - mean);
    lo = lo.cwiseMin(q[i]), hi = hi.cwiseMax(q[i]);
  }
  if (!(hi.x() > lo.x()) || !(hi.y() > lo.y())) throw InputError(path, "", "the scan has no extent in its panel plane");
  std::vector<float> zs(q.size());
  for (size_t i = 0; i < q.size(); ++i) zs[i] = static_cast<float>(q[i].z());
  const double wall = PercentileOf(zs, 0.02);
  const int w = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) * o.pixels_per_m)));
  const int h = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) * o.pixels_per_m)));
  if (static_cast<double>(w) * h > 4e8) {
    throw InputError(path, "", "the render would be " + std::to_string(w) + "x" + std::to_string(h) +
                                   " pixels: is the scan in metres? lower pixels_per_m");
  }
  ImageF height(w, h, 1, NAN), grey(w, h, 1, 0.6f);
  for (size_t i = 0; i < q.size(); ++i) {
    const int x = std::min(w - 1, static_cast<int>((q[i].x() - lo.x()) * o.pixels_per_m));
    const int y = std::min(h - 1, static_cast<int>((hi.y() - q[i].y()) * o.pixels_per_m));
    const float z = static_cast<float>(q[i].z() - wall);
    if (!std::isnan(height.at(x, y)) && height.at(x, y) >= z) continue;
    height.at(x, y) = z;
    if (cloud.schema.colors) {
      const Rgb8 c = cloud.colors[i];
      grey.at(x, y) = static_cast<float>((0.299 * c.r + 0.587 * c.g + 0.114 * c.b) / 255.0);
    }
  }
  FillHoles(&height, &grey, o.fill_holes);
  TrainingPair pair;
  pair.depth = ImageF(w, h, 1);
  ImageF filled = height;
  for (size_t i = 0; i < height.values().size(); ++i) {
    const float z = height.values()[i];
    pair.depth.values()[i] = std::isnan(z) ? 0.0f : static_cast<float>(LevelFromHeight(z, o.depth_m));
    filled.values()[i] = std::isnan(z) ? 0.0f : std::clamp<float>(z, 0, o.depth_m);
  }
  pair.photo = o.relight ? SimulateOldPhoto(o.photo, filled, grey, 1.0 / o.pixels_per_m, o.seed).photo : grey;
  return pair;
}

std::vector<TrainingPair> CutPatches(const PatchOptions& o, const TrainingPair& panel) {
  o.Check();
  CANDI_CHECK(panel.photo.width() == panel.depth.width() && panel.photo.height() == panel.depth.height());
  std::vector<TrainingPair> out;
  const int w = panel.photo.width(), h = panel.photo.height();
  if (w < o.patch || h < o.patch) return out;
  auto starts = [&](int size) {
    std::vector<int> s;
    for (int v = 0; v + o.patch <= size; v += o.stride) s.push_back(v);
    if (s.back() + o.patch < size) s.push_back(size - o.patch);
    return s;
  };
  for (int y0 : starts(h)) {
    for (int x0 : starts(w)) {
      TrainingPair p{ImageF(o.patch, o.patch, 1), ImageF(o.patch, o.patch, 1)};
      size_t valid = 0;
      for (int y = 0; y < o.patch; ++y) {
        for (int x = 0; x < o.patch; ++x) {
          p.photo.at(x, y) = panel.photo.at(x0 + x, y0 + y);
          p.depth.at(x, y) = panel.depth.at(x0 + x, y0 + y);
          valid += p.depth.at(x, y) >= kMinValidLevel;
        }
      }
      if (valid >= o.min_valid_fraction * o.patch * o.patch && valid > 0) out.push_back(std::move(p));
    }
  }
  return out;
}

TrainingPair Augment(const AugmentOptions& o, const TrainingPair& in, uint64_t seed, uint64_t index) {
  o.Check();
  Rng rng(HashIndex(seed, index, 21));
  TrainingPair p = in;
  const int w = p.photo.width(), h = p.photo.height();
  if (rng.Uniform() < o.rotate_probability) {
    const double a = rng.Uniform(-o.max_rotation_deg, o.max_rotation_deg) * 3.14159265358979 / 180;
    const double c = std::cos(a), s = std::sin(a), cx = 0.5 * w - 0.5, cy = 0.5 * h - 0.5;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const double sx = cx + c * (x - cx) - s * (y - cy), sy = cy + s * (x - cx) + c * (y - cy);
        p.photo.at(x, y) = Bilinear(in.photo, sx, sy, 0.0f);
        // Depth: nearest, so no level is invented between a figure and the wall.
        const int nx = static_cast<int>(std::lround(sx)), ny = static_cast<int>(std::lround(sy));
        p.depth.at(x, y) = (nx < 0 || ny < 0 || nx >= w || ny >= h) ? 0.0f : in.depth.at(nx, ny);
      }
    }
  }
  if (rng.Uniform() < o.flip_probability) {
    for (int y = 0; y < h; ++y) {
      std::reverse(&p.photo.at(0, y), &p.photo.at(0, y) + w);
      std::reverse(&p.depth.at(0, y), &p.depth.at(0, y) + w);
    }
  }
  if (rng.Uniform() < o.brightness_probability) {
    const float gain = static_cast<float>(rng.Uniform(0.9, 1.1));
    for (float& v : p.photo.values()) v = std::clamp(v * gain, 0.0f, 1.0f);
  }
  return p;
}

void WritePairs(const std::string& dir, const std::vector<TrainingPair>& pairs, size_t first) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError(dir, "", "cannot create the folder: " + ec.message());
  for (size_t i = 0; i < pairs.size(); ++i) {
    WritePhoto(PairName(dir, first + i, "photo"), pairs[i].photo);
    WriteDepth16(PairName(dir, first + i, "depth"), pairs[i].depth);
  }
}

std::vector<std::string> PairPhotoPaths(const std::string& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) throw InputError(dir, "", "not a folder of pairs");
  std::vector<std::string> photos;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > 10 && name.compare(name.size() - 10, 10, "_photo.png") == 0) {
      photos.push_back(entry.path().string());
    }
  }
  std::sort(photos.begin(), photos.end());
  return photos;
}

std::vector<TrainingPair> ReadPairs(const std::string& dir) {
  std::vector<TrainingPair> pairs;
  for (const std::string& photo : PairPhotoPaths(dir)) {
    const std::string depth = photo.substr(0, photo.size() - 10) + "_depth.png";
    TrainingPair p{ReadPhoto(photo), ReadDepth(depth)};
    if (p.photo.width() != p.depth.width() || p.photo.height() != p.depth.height()) {
      throw InputError(depth, "", "size differs from " + photo);
    }
    pairs.push_back(std::move(p));
  }
  return pairs;
}

}  // namespace candi::relief

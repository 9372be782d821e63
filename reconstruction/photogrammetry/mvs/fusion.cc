#include "reconstruction/photogrammetry/mvs/fusion.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "core/check.h"

namespace candi::photogrammetry {

namespace {

struct Accumulator {
  Eigen::Vector3d position = Eigen::Vector3d::Zero(), color = Eigen::Vector3d::Zero(),
                  normal = Eigen::Vector3d::Zero();
  int count = 0;
  void Add(const DepthNormalMap& m, int x, int y, const Eigen::Vector3d& world) {
    position += world;
    for (int c = 0; c < 3; ++c) color[c] += m.color.at(x, y, c);
    normal += WorldNormal(m, x, y);
    ++count;
  }
  static Eigen::Vector3d WorldNormal(const DepthNormalMap& m, int x, int y) {
    const Eigen::Vector3d n(m.normal.at(x, y, 0), m.normal.at(x, y, 1), m.normal.at(x, y, 2));
    return m.camera.rotation.transpose() * n;
  }
};

Eigen::Vector3d PixelPoint(const DepthNormalMap& m, int x, int y) {
  return m.camera.ToWorld(static_cast<double>(m.depth.at(x, y)) * m.camera.Ray(x + 0.5, y + 0.5));
}

}  // namespace

void FusionOptions::Check() const {
  CANDI_CHECK_OPTION_GE(min_views, 1);
  CANDI_CHECK_OPTION_GT(max_depth_error, 0);
  CANDI_CHECK_OPTION(max_normal_error_deg > 0 && max_normal_error_deg <= 180, max_normal_error_deg,
                     "in (0, 180]");
  CANDI_CHECK_OPTION_GT(max_reprojection_error_px, 0);
}

PointCloud FuseDepthMaps(const FusionOptions& options, const std::vector<DepthNormalMap>& maps,
                         const ProgressCallback& progress) {
  options.Check();
  PointSchema schema;
  schema.colors = true;
  schema.normals = true;
  PointCloud cloud;
  cloud.SetSchema(schema);
  const double cos_normal = std::cos(options.max_normal_error_deg * 3.14159265358979323846 / 180);
  std::vector<std::vector<uint8_t>> used(maps.size());
  uint64_t total = 0, done = 0;
  for (size_t v = 0; v < maps.size(); ++v) {
    used[v].assign(maps[v].depth.values().size(), 0);
    total += maps[v].depth.values().size();
  }
  for (size_t v = 0; v < maps.size(); ++v) {
    const DepthNormalMap& m = maps[v];
    for (int y = 0; y < m.depth.height(); ++y) {
      for (int x = 0; x < m.depth.width(); ++x) {
        const size_t i = static_cast<size_t>(y) * m.depth.width() + x;
        if (used[v][i] || !(m.depth.at(x, y) > 0)) continue;
        const Eigen::Vector3d X = PixelPoint(m, x, y);
        const Eigen::Vector3d n = Accumulator::WorldNormal(m, x, y);
        if (!X.allFinite() || !n.allFinite()) continue;
        Accumulator acc;
        acc.Add(m, x, y, X);
        std::vector<std::pair<size_t, size_t>> members{{v, i}};
        for (size_t s = 0; s < maps.size(); ++s) {
          if (s == v) continue;
          const DepthNormalMap& o = maps[s];
          const Eigen::Vector3d c = o.camera.ToCamera(X);
          if (!(c.z() > 0)) continue;
          const Eigen::Vector2d uv = o.camera.Project(c);
          if (!(uv.x() >= 0 && uv.y() >= 0 && uv.x() < o.depth.width() && uv.y() < o.depth.height())) continue;
          const int sx = static_cast<int>(uv.x()), sy = static_cast<int>(uv.y());
          const size_t j = static_cast<size_t>(sy) * o.depth.width() + sx;
          const double ds = o.depth.at(sx, sy);
          if (used[s][j] || !(ds > 0) || std::abs(ds - c.z()) > options.max_depth_error * c.z()) continue;
          if (Accumulator::WorldNormal(o, sx, sy).dot(n) < cos_normal) continue;
          const Eigen::Vector3d Xs = PixelPoint(o, sx, sy);
          if ((m.camera.Project(m.camera.ToCamera(Xs)) - Eigen::Vector2d(x + 0.5, y + 0.5)).norm() >
              options.max_reprojection_error_px)
            continue;
          acc.Add(o, sx, sy, Xs);
          members.push_back({s, j});
        }
        if (acc.count < options.min_views) continue;
        for (const auto& [mv, mi] : members) used[mv][mi] = 1;
        cloud.positions.push_back(acc.position / acc.count);
        const Eigen::Vector3d rgb = acc.color / acc.count;
        cloud.colors.push_back(Rgb8{static_cast<uint8_t>(std::lround(rgb[0])),
                                    static_cast<uint8_t>(std::lround(rgb[1])),
                                    static_cast<uint8_t>(std::lround(rgb[2]))});
        const Eigen::Vector3d mean_normal = acc.normal.normalized();
        cloud.normals.push_back(mean_normal.cast<float>());
      }
      done += m.depth.width();
      if (progress && (y % 16 == 0 || y + 1 == m.depth.height())) progress(done, total);
    }
  }
  return cloud;
}

}  // namespace candi::photogrammetry

#include "reconstruction/photogrammetry/scenes/dense_truth.h"

#include <cmath>
#include <limits>

#include "core/check.h"
#include "core/parallel.h"
#include "reconstruction/photogrammetry/registration/point_index.h"

namespace candi::photogrammetry {

std::vector<DenseTruthScore> ScoreDenseAgainstTruth(const std::vector<SyntheticView>& views,
                                                    const std::vector<Eigen::Vector3d>& points,
                                                    const std::vector<double>& taus, int stride) {
  CANDI_CHECK(stride >= 1) << "stride " << stride;
  // Each point's distance to the surface along the views' rays.
  std::vector<double> error(points.size(), std::numeric_limits<double>::infinity());
  ParallelFor(size_t{0}, points.size(), [&](size_t i) {
    const Eigen::Vector3d& p = points[i];
    if (!p.allFinite()) return;
    for (const SyntheticView& v : views) {
      const PinholeCamera& cam = v.camera;
      const Eigen::Vector3d c = cam.ToCamera(p);
      if (!(c.z() > 0)) continue;
      const Eigen::Vector2d uv = cam.Project(c);
      if (!(uv.x() >= 0 && uv.y() >= 0 && uv.x() < cam.width && uv.y() < cam.height)) continue;
      const double truth = v.depth.at(static_cast<int>(uv.x()), static_cast<int>(uv.y()));
      if (!(truth > 0)) continue;
      error[i] = std::min(error[i], std::abs(truth / c.z() - 1.0) * c.norm());
    }
  });
  // The surface sample and each sample's distance to the nearest point.
  std::vector<Eigen::Vector3f> surface;
  for (const SyntheticView& v : views)
    for (int y = stride / 2; y < v.depth.height(); y += stride)
      for (int x = stride / 2; x < v.depth.width(); x += stride)
        if (v.depth.at(x, y) > 0)
          surface.push_back(v.camera.ToWorld(v.depth.at(x, y) * v.camera.Ray(x + 0.5, y + 0.5)).cast<float>());
  std::vector<Eigen::Vector3f> cloud;
  for (const Eigen::Vector3d& p : points)
    if (p.allFinite()) cloud.push_back(p.cast<float>());
  const PointIndex index(cloud);
  const std::vector<double> d2 = index.NearestSquaredDistances(surface, Eigen::Matrix4d::Identity());
  std::vector<DenseTruthScore> out;
  for (double tau : taus) {
    DenseTruthScore s;
    s.tau = tau;
    size_t near = 0, covered = 0;
    for (double e : error) near += e <= tau;
    for (double d : d2) covered += d <= tau * tau;
    s.accuracy = points.empty() ? 0 : static_cast<double>(near) / points.size();
    s.completeness = surface.empty() ? 0 : static_cast<double>(covered) / surface.size();
    s.f_score = s.accuracy + s.completeness > 0 ? 2 * s.accuracy * s.completeness / (s.accuracy + s.completeness) : 0;
    out.push_back(s);
  }
  return out;
}

}  // namespace candi::photogrammetry

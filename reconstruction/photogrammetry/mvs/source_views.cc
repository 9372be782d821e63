#include "reconstruction/photogrammetry/mvs/source_views.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "core/check.h"

namespace candi::photogrammetry {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kMaxAngleDeg = 75;
constexpr size_t kMaxSamples = 1000;  // per pair: the medians of the first points (point order)

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180 / kPi;
}

struct PairStats {
  size_t shared = 0;
  std::vector<float> angle, log_ratio;  // degrees; |log(d_a / d_b)|
};

double Median(std::vector<float>* v) {
  const size_t k = v->size() / 2;
  std::nth_element(v->begin(), v->begin() + k, v->end());
  return (*v)[k];
}

}  // namespace

void SourceViewOptions::Check() const {
  CANDI_CHECK_OPTION_IN(num_sources, 1, 32);
  CANDI_CHECK_OPTION_IN(num_check_views, num_sources, 64);
  CANDI_CHECK_OPTION(min_triangulation_angle_deg >= 0 && min_triangulation_angle_deg < 60,
                     min_triangulation_angle_deg, "in [0, 60)");
  CANDI_CHECK_OPTION(max_distance_ratio >= 1 && std::isfinite(max_distance_ratio), max_distance_ratio, ">= 1");
}

std::vector<ViewLinks> SelectSourceViewsFromTracks(const SourceViewOptions& options,
                                                          const std::vector<PinholeCamera>& cameras,
                                                          const std::vector<Eigen::Vector3d>& points,
                                                          const std::vector<std::vector<int>>& point_views) {
  options.Check();
  CANDI_CHECK(points.size() == point_views.size()) << points.size() << " points, " << point_views.size() << " tracks";
  const int n = static_cast<int>(cameras.size());
  std::vector<Eigen::Vector3d> centres;
  for (const PinholeCamera& c : cameras) centres.push_back(c.Center());
  std::unordered_map<uint64_t, PairStats> pairs;
  std::vector<int> views;
  for (size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector3d& X = points[k];
    if (!X.allFinite()) continue;
    views = point_views[k];
    std::sort(views.begin(), views.end());
    views.erase(std::unique(views.begin(), views.end()), views.end());
    for (size_t i = 0; i < views.size(); ++i) {
      const int a = views[i];
      CANDI_CHECK(a >= 0 && a < n) << "point " << k << " names view " << a << " of " << n;
      for (size_t j = i + 1; j < views.size(); ++j) {
        const int b = views[j];
        CANDI_CHECK(b >= 0 && b < n) << "point " << k << " names view " << b << " of " << n;
        PairStats& s = pairs[static_cast<uint64_t>(a) * n + b];
        ++s.shared;
        if (s.angle.size() >= kMaxSamples) continue;
        const Eigen::Vector3d ra = centres[a] - X, rb = centres[b] - X;
        const double da = ra.norm(), db = rb.norm();
        if (!(da > 0 && db > 0)) continue;
        s.angle.push_back(static_cast<float>(AngleDeg(ra, rb)));
        s.log_ratio.push_back(static_cast<float>(std::abs(std::log(da / db))));
      }
    }
  }
  // Candidates per photo: (shared points, index), kept by the angle and distance rules.
  std::vector<std::vector<std::pair<size_t, int>>> candidates(n);
  const double max_log_ratio = std::log(options.max_distance_ratio);
  for (auto& [key, s] : pairs) {
    if (s.angle.empty()) continue;
    const double angle = Median(&s.angle), log_ratio = Median(&s.log_ratio);
    if (angle < options.min_triangulation_angle_deg || angle > kMaxAngleDeg || log_ratio > max_log_ratio + 1e-12)
      continue;
    const int a = static_cast<int>(key / n), b = static_cast<int>(key % n);
    candidates[a].push_back({s.shared, b});
    candidates[b].push_back({s.shared, a});
  }
  std::vector<ViewLinks> links(n);
  for (int r = 0; r < n; ++r) {
    std::vector<std::pair<size_t, int>>& c = candidates[r];
    std::sort(c.begin(), c.end(), [](const auto& x, const auto& y) {
      return x.first != y.first ? x.first > y.first : x.second < y.second;
    });
    for (size_t k = 0; k < c.size(); ++k) {
      if (static_cast<int>(k) < options.num_sources) links[r].sources.push_back(c[k].second);
      if (static_cast<int>(k) < options.num_check_views) links[r].checks.push_back(c[k].second);
    }
  }
  return links;
}

ViewLinks SelectSourceViewsByAngle(const SourceViewOptions& options, const std::vector<PinholeCamera>& cameras, int r,
                                   double depth) {
  const PinholeCamera& ref = cameras[r];
  const Eigen::Vector3d p = ref.ToWorld(Eigen::Vector3d(0, 0, depth));
  std::vector<std::pair<double, int>> scored;
  for (int s = 0; s < static_cast<int>(cameras.size()); ++s) {
    if (s == r) continue;
    const PinholeCamera& src = cameras[s];
    const double angle = AngleDeg(ref.Center() - p, src.Center() - p);
    const Eigen::Vector3d c = src.ToCamera(p);
    if (!(c.z() > 0) || angle < options.min_triangulation_angle_deg || angle > kMaxAngleDeg) continue;
    const Eigen::Vector2d uv = src.Project(c);
    if (uv.x() < 0 || uv.y() < 0 || uv.x() >= src.width || uv.y() >= src.height) continue;
    scored.push_back({std::abs(angle - 15.0), s});
  }
  std::sort(scored.begin(), scored.end());
  ViewLinks out;
  std::vector<uint8_t> listed(cameras.size(), 0);
  listed[r] = 1;
  for (size_t k = 0; k < scored.size(); ++k) {
    if (static_cast<int>(k) < options.num_sources) out.sources.push_back(scored[k].second);
    if (static_cast<int>(k) < options.num_check_views) out.checks.push_back(scored[k].second);
    listed[scored[k].second] = 1;
  }
  for (size_t s = 0; s < cameras.size() && static_cast<int>(out.checks.size()) < options.num_check_views; ++s)
    if (!listed[s]) out.checks.push_back(static_cast<int>(s));
  return out;
}

std::vector<std::vector<int>> NeighbourViews(const std::vector<ViewLinks>& links) {
  std::vector<std::vector<int>> lists;
  for (const ViewLinks& l : links) {
    lists.push_back(l.sources);
    lists.back().insert(lists.back().end(), l.checks.begin(), l.checks.end());
  }
  return NeighbourViews(lists);
}

std::vector<std::vector<int>> NeighbourViews(const std::vector<std::vector<int>>& lists) {
  std::vector<std::vector<int>> out(lists.size());
  for (size_t r = 0; r < lists.size(); ++r) {
    for (int s : lists[r]) {
      CANDI_CHECK(s >= 0 && static_cast<size_t>(s) < lists.size() && static_cast<size_t>(s) != r)
          << "view " << r << " lists view " << s;
      out[r].push_back(s);
      out[s].push_back(static_cast<int>(r));
    }
  }
  for (std::vector<int>& n : out) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  return out;
}

std::string PatchMatchConfig(const std::vector<std::string>& names, const std::vector<ViewLinks>& links) {
  CANDI_CHECK(names.size() == links.size()) << names.size() << " names, " << links.size() << " source lists";
  std::string out;
  for (size_t r = 0; r < names.size(); ++r) {
    out += names[r] + "\n";
    const std::vector<int>& sources = links[r].sources;
    for (size_t k = 0; k < sources.size(); ++k) out += (k ? ", " : "") + names[sources[k]];
    out += "\n";
  }
  return out;
}

}  // namespace candi::photogrammetry

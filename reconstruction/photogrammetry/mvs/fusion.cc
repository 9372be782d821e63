#include "reconstruction/photogrammetry/mvs/fusion.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/check.h"
#include "core/parallel.h"

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

class MemoryMaps : public FusionMaps {
 public:
  explicit MemoryMaps(const std::vector<DepthNormalMap>& maps) : maps_(maps) {}
  size_t size() const override { return maps_.size(); }
  std::shared_ptr<const DepthNormalMap> Load(int view) const override {
    return std::shared_ptr<const DepthNormalMap>(&maps_[view], [](const DepthNormalMap*) {});
  }

 private:
  const std::vector<DepthNormalMap>& maps_;
};

}  // namespace

void FusionOptions::Check() const {
  CANDI_CHECK_OPTION_GE(min_views, 1);
  CANDI_CHECK_OPTION_GT(max_depth_error, 0);
  CANDI_CHECK_OPTION(max_normal_error_deg > 0 && max_normal_error_deg <= 180, max_normal_error_deg,
                     "in (0, 180]");
  CANDI_CHECK_OPTION_GT(max_reprojection_error_px, 0);
  CANDI_CHECK_OPTION_GE(max_tile_views, 1);
}

FusionTiles::FusionTiles(const std::vector<Eigen::Vector3d>& points, const std::vector<std::vector<int>>& point_views,
                         int max_views, size_t min_points) {
  CANDI_CHECK(points.size() == point_views.size()) << points.size() << " points, " << point_views.size() << " tracks";
  std::vector<int> idx;
  for (size_t k = 0; k < points.size(); ++k)
    if (points[k].allFinite()) idx.push_back(static_cast<int>(k));
  leaves_ = 0;
  Build(&idx, 0, idx.size(), points, point_views, max_views, std::max<size_t>(min_points, 2));
}

int FusionTiles::Build(std::vector<int>* idx, size_t lo, size_t hi, const std::vector<Eigen::Vector3d>& points,
                       const std::vector<std::vector<int>>& point_views, int max_views, size_t min_points) {
  const int node = static_cast<int>(nodes_.size());
  nodes_.emplace_back();
  std::vector<int> views;
  Eigen::Vector3d lo_corner = Eigen::Vector3d::Constant(INFINITY), hi_corner = -lo_corner;
  for (size_t k = lo; k < hi; ++k) {
    const int p = (*idx)[k];
    views.insert(views.end(), point_views[p].begin(), point_views[p].end());
    lo_corner = lo_corner.cwiseMin(points[p]);
    hi_corner = hi_corner.cwiseMax(points[p]);
  }
  std::sort(views.begin(), views.end());
  const size_t distinct = std::unique(views.begin(), views.end()) - views.begin();
  if (static_cast<int>(distinct) > max_views && hi - lo >= min_points) {
    // The longest side first; where its median cannot split the points (walls are planes: many
    // share one coordinate), the split moves to the next larger value, then to the other sides.
    int axes[3] = {0, 1, 2};
    const Eigen::Vector3d extent = hi_corner - lo_corner;
    std::sort(axes, axes + 3, [&](int a, int b) { return extent[a] != extent[b] ? extent[a] > extent[b] : a < b; });
    const size_t mid = lo + (hi - lo) / 2;
    for (int axis : axes) {
      auto less = [&](int a, int b) {
        return points[a][axis] != points[b][axis] ? points[a][axis] < points[b][axis] : a < b;
      };
      std::nth_element(idx->begin() + lo, idx->begin() + mid, idx->begin() + hi, less);
      double split = points[(*idx)[mid]][axis];
      size_t below = 0;
      double above = INFINITY;  // the least value above the median
      for (size_t k = lo; k < hi; ++k) {
        const double v = points[(*idx)[k]][axis];
        below += v < split;
        if (v > split) above = std::min(above, v);
      }
      if (below == 0) split = above;  // everything below is nothing: the median is the least value
      if (!std::isfinite(split)) continue;  // all equal on this side
      // Points below the split go first.
      size_t cut = lo;
      for (size_t k = lo; k < hi; ++k)
        if (points[(*idx)[k]][axis] < split) std::swap((*idx)[k], (*idx)[cut++]);
      if (cut == lo || cut == hi) continue;
      std::sort(idx->begin() + lo, idx->begin() + cut);  // a fixed order whatever nth_element did
      std::sort(idx->begin() + cut, idx->begin() + hi);
      nodes_[node].axis = axis;
      nodes_[node].split = split;
      Build(idx, lo, cut, points, point_views, max_views, min_points);
      const int second = Build(idx, cut, hi, points, point_views, max_views, min_points);
      nodes_[node].second = second;
      return node;
    }
  }
  nodes_[node].leaf = leaves_++;
  return node;
}

int FusionTiles::Leaf(const Eigen::Vector3d& p) const {
  if (nodes_.empty()) return 0;
  int n = 0;
  while (nodes_[n].axis >= 0) n = p[nodes_[n].axis] >= nodes_[n].split ? nodes_[n].second : n + 1;
  return nodes_[n].leaf;
}

std::vector<std::vector<int>> TileViews(const FusionTiles& tiles, const FusionMaps& maps) {
  std::vector<std::vector<uint8_t>> seen(maps.size());
  ParallelFor(size_t{0}, maps.size(), [&](size_t v) {
    seen[v].assign(tiles.count(), 0);
    const std::shared_ptr<const DepthNormalMap> m = maps.Load(static_cast<int>(v));
    for (int y = 0; y < m->depth.height(); ++y)
      for (int x = 0; x < m->depth.width(); ++x)
        if (m->depth.at(x, y) > 0) seen[v][tiles.Leaf(PixelPoint(*m, x, y))] = 1;
  });
  std::vector<std::vector<int>> out(tiles.count());
  for (size_t v = 0; v < seen.size(); ++v)
    for (int t = 0; t < tiles.count(); ++t)
      if (seen[v][t]) out[t].push_back(static_cast<int>(v));
  return out;
}

PointCloud FusedCloud() {
  PointSchema schema;
  schema.colors = true;
  schema.normals = true;
  PointCloud cloud;
  cloud.SetSchema(schema);
  return cloud;
}

PointCloud FuseTile(const FusionOptions& options, const FusionTiles& tiles, int tile, const std::vector<int>& views,
                    const std::vector<std::vector<int>>& neighbours, const FusionMaps& maps,
                    const std::function<void(uint64_t)>& visited) {
  options.Check();
  CANDI_CHECK(neighbours.size() == maps.size()) << neighbours.size() << " neighbour lists, " << maps.size() << " maps";
  PointCloud cloud = FusedCloud();
  const double cos_normal = std::cos(options.max_normal_error_deg * 3.14159265358979323846 / 180);
  // The cell's maps, by slot; slot_of[view] = -1 outside the cell.
  std::vector<int> slot_of(maps.size(), -1);
  std::vector<std::shared_ptr<const DepthNormalMap>> held;
  std::vector<std::vector<uint8_t>> used;  // 1: used, 2: outside the cell or no depth
  for (int v : views) {
    slot_of[v] = static_cast<int>(held.size());
    held.push_back(maps.Load(v));
    const DepthNormalMap& m = *held.back();
    std::vector<uint8_t> mark(m.depth.values().size(), 2);
    for (int y = 0; y < m.depth.height(); ++y)
      for (int x = 0; x < m.depth.width(); ++x)
        if (m.depth.at(x, y) > 0 && tiles.Leaf(PixelPoint(m, x, y)) == tile)
          mark[static_cast<size_t>(y) * m.depth.width() + x] = 0;
    used.push_back(std::move(mark));
  }
  for (size_t a = 0; a < views.size(); ++a) {
    const DepthNormalMap& m = *held[a];
    std::vector<int> near;  // the seed view's neighbours in this cell
    for (int s : neighbours[views[a]])
      if (slot_of[s] >= 0) near.push_back(slot_of[s]);
    for (int y = 0; y < m.depth.height(); ++y) {
      for (int x = 0; x < m.depth.width(); ++x) {
        const size_t i = static_cast<size_t>(y) * m.depth.width() + x;
        if (used[a][i]) continue;
        const Eigen::Vector3d X = PixelPoint(m, x, y);
        const Eigen::Vector3d n = Accumulator::WorldNormal(m, x, y);
        if (!X.allFinite() || !n.allFinite()) continue;
        Accumulator acc;
        acc.Add(m, x, y, X);
        std::vector<std::pair<size_t, size_t>> members{{a, i}};
        for (int b : near) {
          const DepthNormalMap& o = *held[b];
          const Eigen::Vector3d c = o.camera.ToCamera(X);
          if (!(c.z() > 0)) continue;
          const Eigen::Vector2d uv = o.camera.Project(c);
          if (!(uv.x() >= 0 && uv.y() >= 0 && uv.x() < o.depth.width() && uv.y() < o.depth.height())) continue;
          const int sx = static_cast<int>(uv.x()), sy = static_cast<int>(uv.y());
          const size_t j = static_cast<size_t>(sy) * o.depth.width() + sx;
          const double ds = o.depth.at(sx, sy);
          if (used[b][j] || !(ds > 0) || std::abs(ds - c.z()) > options.max_depth_error * c.z()) continue;
          if (Accumulator::WorldNormal(o, sx, sy).dot(n) < cos_normal) continue;
          const Eigen::Vector3d Xs = PixelPoint(o, sx, sy);
          if ((m.camera.Project(m.camera.ToCamera(Xs)) - Eigen::Vector2d(x + 0.5, y + 0.5)).norm() >
              options.max_reprojection_error_px)
            continue;
          acc.Add(o, sx, sy, Xs);
          members.push_back({static_cast<size_t>(b), j});
        }
        if (acc.count < options.min_views) continue;
        for (const auto& [mv, mi] : members) used[mv][mi] = 1;
        cloud.positions.push_back(acc.position / acc.count);
        const Eigen::Vector3d rgb = acc.color / acc.count;
        cloud.colors.push_back(Rgb8{static_cast<uint8_t>(std::lround(rgb[0])),
                                    static_cast<uint8_t>(std::lround(rgb[1])),
                                    static_cast<uint8_t>(std::lround(rgb[2]))});
        cloud.normals.push_back(acc.normal.normalized().cast<float>());
      }
      if (visited) visited(m.depth.width());
    }
  }
  return cloud;
}

PointCloud FuseDepthMaps(const FusionOptions& options, const std::vector<DepthNormalMap>& maps,
                         const ProgressCallback& progress) {
  options.Check();
  const MemoryMaps source(maps);
  std::vector<ViewLinks> links;
  std::vector<int> views;
  uint64_t total = 0, done = 0;
  for (size_t v = 0; v < maps.size(); ++v) {
    links.push_back({maps[v].source_views, maps[v].check_views});
    views.push_back(static_cast<int>(v));
    total += maps[v].depth.values().size();
  }
  return FuseTile(options, FusionTiles(), 0, views, NeighbourViews(links), source, [&](uint64_t n) {
    done += n;
    if (progress && (done == total || done % 4096 < n)) progress(done, total);
  });
}

}  // namespace candi::photogrammetry

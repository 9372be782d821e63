// Fusion of depth and normal maps into one coloured point cloud with normals (candi's own, in the
// spirit of COLMAP's StereoFusion): every valid pixel not yet used seeds a point; its 3D point is
// projected into the seed view's neighbours (its sources and check views, and the views that list
// it: source_views.h; never every view), and the pixel it lands on joins when that view's depth agrees (relative
// tolerance), its normal agrees (angle) and it reprojects within a pixel tolerance. Points seen by
// at least `min_views` views are kept: mean position, mean colour, mean normal.
//
// Tiles: space is cut into cells (FusionTiles: median splits of the sparse points until each
// cell's points are seen by at most `max_tile_views` views). A pixel belongs to the cell its 3D
// point falls in; a cell is fused from the maps of the views that have pixels in it, and only its
// own pixels seed or join. So every pixel is used at most once, cells are independent (parallel,
// on any machine) and a cell holds only its views' maps. The points come out cell by cell, in
// cell order, each cell's in seed order.
//
// Frames: positions in the model frame of the cameras (a LocalFrame at the origin); normals world-
// frame unit vectors. Deterministic: the same bytes whatever the thread count.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "core/point_cloud.h"
#include "core/progress.h"
#include "reconstruction/photogrammetry/mvs/patch_match.h"

namespace candi::photogrammetry {

struct FusionOptions {
  int min_views = 3;                 // views agreeing on a point (the seed included), >= 1
  double max_depth_error = 0.01;     // |d' - d| / d, > 0
  double max_normal_error_deg = 20;  // angle between normals, degrees, in (0, 180]
  double max_reprojection_error_px = 2;  // pixels, > 0
  int max_tile_views = 32;           // tiles: views whose sparse points a cell may hold, >= 1
  void Check() const;
};

// The cells of space fusion works in: a binary tree of axis-aligned splits; leaves are numbered
// 0..count-1 in depth-first order.
class FusionTiles {
 public:
  FusionTiles() = default;  // one cell: everything
  // Median splits of `points` (each seen by `point_views[k]`) along the longest side of the cell's
  // bounding box, until a cell's points are seen by at most `max_views` views or it holds fewer
  // than `min_points` points.
  FusionTiles(const std::vector<Eigen::Vector3d>& points, const std::vector<std::vector<int>>& point_views,
              int max_views, size_t min_points = 64);
  int count() const { return leaves_; }
  int Leaf(const Eigen::Vector3d& p) const;  // the cell of a point (NaN: cell 0's side of every split)

 private:
  struct Node {
    int axis = -1;          // -1: a leaf
    double split = 0;       // < split: first child, the next node; >= split: `second`
    int second = -1;        // node index of the second child
    int leaf = 0;           // leaf number when axis == -1
  };
  int Build(std::vector<int>* idx, size_t lo, size_t hi, const std::vector<Eigen::Vector3d>& points,
            const std::vector<std::vector<int>>& point_views, int max_views, size_t min_points);
  std::vector<Node> nodes_;
  int leaves_ = 1;
};

// Where fusion gets its maps: in memory or read from disk as a cell needs them.
class FusionMaps {
 public:
  virtual ~FusionMaps() = default;
  virtual size_t size() const = 0;
  // The view's map (depth, normal, colour, camera at the working resolution).
  virtual std::shared_ptr<const DepthNormalMap> Load(int view) const = 0;
};

// For each cell, the views with a valid pixel in it (ascending): one pass over the maps, parallel
// over views.
std::vector<std::vector<int>> TileViews(const FusionTiles& tiles, const FusionMaps& maps);

// The points of one cell. `neighbours[v]` as NeighbourViews gives them; `views` the cell's views
// (TileViews).
// `visited(n)`: n more pixels of the cell's views looked at.
PointCloud FuseTile(const FusionOptions& options, const FusionTiles& tiles, int tile, const std::vector<int>& views,
                    const std::vector<std::vector<int>>& neighbours, const FusionMaps& maps,
                    const std::function<void(uint64_t)>& visited = nullptr);

// The empty cloud fusion writes: positions, colours and normals.
PointCloud FusedCloud();

// In memory, one cell: the maps' source_views and check_views give the neighbours. Progress: pixels visited.
PointCloud FuseDepthMaps(const FusionOptions& options, const std::vector<DepthNormalMap>& maps,
                         const ProgressCallback& progress = nullptr);

}  // namespace candi::photogrammetry

// Source views for dense stereo: for each photo, the photos it is matched against (its sources)
// and the photos its depth is checked against (its check views: the consistency filter and
// fusion), chosen once and used by every stage; never every view.
//
// From the sparse model (as COLMAP's patch_match_stereo chooses them, Model::GetMaxOverlapping-
// Images): two photos are candidates when they see sparse points in common; a candidate is kept
// when the median triangulation angle over those points is at least `min_triangulation_angle_deg`
// and at most 75 degrees, and the median ratio of the points' distances to the two centres is
// within [1 / max_distance_ratio, max_distance_ratio] (a source much nearer or farther sees the
// surface at another scale, where the windows do not correlate); kept candidates are ranked by the
// number of points shared (more first, then the lower index). (Weighting the points by angle and
// scale, as Goesele et al. 2007 do, gave fewer points on the real Sceaux photos: 342 k against
// 360 k, 98.0 % of OpenMVS's cloud covered against 98.7 %.) The first `num_sources` are the
// sources, the first `num_check_views` the check views (as COLMAP's fusion checks up to 50
// overlapping images and its filter the sources).
//
// Without tracks (a model written with cameras and points but no observations), the geometric
// rule: the triangulation angle at the point on the reference's optical axis at `depth`, angles
// near 15 degrees first; this is the rule candi used for every photo before the sparse selection.
// The check views are then the ranked sources' candidates followed by every other view (index
// order), up to `num_check_views`: for a dozen photos, every photo, as candi checked before.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "reconstruction/photogrammetry/pinhole_camera.h"

namespace candi::photogrammetry {

struct SourceViewOptions {
  int num_sources = 4;                     // per photo, [1, 32]
  int num_check_views = 12;                // per photo, [num_sources, 64]
  double min_triangulation_angle_deg = 2;  // median over the shared points, [0, 60)
  double max_distance_ratio = 2;           // median distance ratio, >= 1
  void Check() const;
};

// A photo's views (indices into the photos), ranked.
struct ViewLinks {
  std::vector<int> sources;  // PatchMatch's sources
  std::vector<int> checks;   // the consistency filter's and fusion's views
};

// The views of every photo from the sparse points and, per point, the photos that observe it
// (`point_views[k]`, indices into `cameras`; duplicates are counted once). Deterministic.
std::vector<ViewLinks> SelectSourceViewsFromTracks(const SourceViewOptions& options,
                                                          const std::vector<PinholeCamera>& cameras,
                                                          const std::vector<Eigen::Vector3d>& points,
                                                          const std::vector<std::vector<int>>& point_views);

// The geometric rule for reference `r` (no tracks): see above.
ViewLinks SelectSourceViewsByAngle(const SourceViewOptions& options,
                                          const std::vector<PinholeCamera>& cameras, int r, double depth);

// The neighbours of every photo: its listed views and the photos that list it, ascending.
std::vector<std::vector<int>> NeighbourViews(const std::vector<std::vector<int>>& lists);
// The same over the sources and check views together: the views a photo's depth meets.
std::vector<std::vector<int>> NeighbourViews(const std::vector<ViewLinks>& links);

// COLMAP's stereo/patch-match.cfg: per photo its name, then its sources' names joined by ", "
// (COLMAP's patch_match_stereo reads the file as it is). Pure.
std::string PatchMatchConfig(const std::vector<std::string>& names, const std::vector<ViewLinks>& links);

}  // namespace candi::photogrammetry

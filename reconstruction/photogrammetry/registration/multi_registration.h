// Many-scan registration: N scans (e.g. terrestrial laser scans, each in its own scanner frame)
// with rough start poses world_from_scan are brought into one consistent world frame.
//
// Steps:
//  1. Each scan is voxel-thinned (`voxel`) and its normals estimated (PCA, point_normals.h).
//  2. Candidate pairs: scans whose world bounding boxes (under the start poses, grown by
//     max_correspondence_distance) intersect.
//  3. Each candidate pair is refined by point-to-plane ICP (RegisterPointClouds): the moving
//     scan's points thinned further to icp_voxel onto all the fixed scan's points, first with
//     max_correspondence_distance, then with solve_distance. It is accepted when neither stage
//     lost its overlap and the fine stage's overlap (share of the moving scan's points within
//     solve_distance of the fixed scan) is >= min_overlap; a fine stage that stopped at its
//     iteration limit is accepted with a note in `reason`. An accepted pair's relative pose is
//     then refined by `pair_rounds` rounds of the global solve's robust terms (5.) on the two
//     scans alone: the pair's own best fit.
//  4. The accepted pairs form a graph; the component that holds the anchor (the fixed scans, else
//     the scans with control targets, else scan 0) is registered; every scan outside it is
//     reported unconnected and keeps its start pose. Poses start from a maximum-overlap spanning
//     tree of the pairwise ICP results (then, without fixed scans but with >= 3 control targets,
//     moved rigidly onto the targets).
//  5. Global solve (Ceres, Levenberg-Marquardt): all poses of the component at once, minimising
//     point-to-plane distances of correspondences re-found under the current poses (both
//     directions of every accepted pair, up to correspondences_per_pair each, nearest neighbour
//     within solve_distance) with a Huber loss of scale loss_scale, plus the control targets
//     (residual / accuracy); fixed scans (or, without fixed scans and targets, the anchor scan)
//     held. Repeated outer_iterations times (or until no pose moves by more than 1e-5 m / 1e-6
//     rad), so loops close over the whole graph rather than pair by pair.
//
// Precision: all maths is done relative to one integer origin (the rounded centre of the start
// stations, local_points.h) in double; float only for the kd-trees, relative to each scan's own
// origin. Survey coordinates (E ~ 5e5, N ~ 4e6 m) keep sub-millimetre.
// Determinism: the same input gives the same bytes whatever the thread count (pairs are refined
// in parallel, each into its own slot; correspondences and Ceres run single-threaded).
// Failure: bad options throw std::invalid_argument; bad input (no scans, sizes that differ, an
// empty scan, a non-finite point or pose, a target naming a scan out of range) throws InputError.
// An unconverged solve is a result (`converged`, `message`), not an exception.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/point_cloud.h"
#include "core/progress.h"
#include "core/transform.h"
#include "reconstruction/photogrammetry/georef/georef.h"

namespace candi::photogrammetry {

struct MultiRegistrationOptions {
  double max_correspondence_distance = 1.0;  // m, > 0: the coarse ICP's pairing distance
  double solve_distance = 0.1;               // m, (0, max_correspondence_distance]: fine ICP and
                                             // the global solve's pairing distance
  int icp_iterations = 60;                   // per ICP stage, [1, 100000]
  double voxel = 0.1;                        // m, >= 0: thinning before everything; 0 = off
  double icp_voxel = 0.25;                   // m, >= 0: further thinning for ICP; 0 = off
  int pair_rounds = 3;                       // robust refinement rounds per accepted pair, [0, 100]
  double min_overlap = 0.1;                  // [0, 1]: a pair's overlap needed to accept it
  double loss_scale = 0.01;                  // m, > 0: Huber scale of the point-to-plane terms
  int outer_iterations = 4;                  // global re-pairing rounds, [1, 100]
  int correspondences_per_pair = 2000;       // per direction, [10, 10000000]
  int normal_neighbours = 16;                // k for the normals, [3, 1000]
  std::vector<int> fixed_scans;              // scan indices held at their start pose
  void Check() const;  // throws std::invalid_argument("MultiRegistrationOptions::field = ...")
};

// A surveyed point seen in one scan (e.g. a target's centre picked in the scan).
struct ScanTarget {
  std::string name;
  int scan = 0;                                       // index into the scans
  Eigen::Vector3d in_scan = Eigen::Vector3d::Zero();  // in the scan's frame, m
  Eigen::Vector3d world = Eigen::Vector3d::Zero();    // surveyed world coordinates, m
  TargetRole role = TargetRole::kControl;             // control: in the solve; check: verified
  double accuracy = 0.005;                            // 1-sigma, m, > 0 (weights the solve)
};

struct PairReport {
  int moving = 0, fixed = 0;  // scan indices (moving < fixed)
  bool accepted = false;
  std::string reason;     // "accepted", or why not (ICP status, overlap below min)
  double overlap = 0;     // fine ICP's overlap after, [0, 1]
  double rms_before = 0;  // m, nearest-point RMS under the start poses (coarse distance)
  double rms_after = 0;   // m, after the pairwise ICP (solve_distance); NaN: none
  double rms_global = 0;  // m, point-to-plane RMS under the final poses; NaN: none
  // The pair's own best relative pose (ICP, then the robust rounds), scan frames:
  // x_in_fixed_scan = fixed_from_moving * x_in_moving_scan. Identity when ICP found no overlap.
  Rigid3 fixed_from_moving;
  // The final relative pose against the pairwise ICP's (fixed_from_moving): how far the global
  // solution is from this pair's own best fit. Zero on a tree edge of a consistent graph.
  double discrepancy_translation = 0;   // m
  double discrepancy_rotation_deg = 0;  // degrees
};

struct ScanReport {
  bool connected = false;          // in the anchor's component (else: start pose kept)
  bool fixed = false;              // held at its start pose
  double translation_change = 0;   // m: |t_final - t_start| of world_from_scan
  double rotation_change_deg = 0;  // degrees: angle of R_final R_start^T
  double residual_rms = 0;         // m: point-to-plane RMS of its final correspondences; NaN
  int correspondences = 0;         // its final correspondences (as either side)
};

// A cycle of the accepted-pair graph (one per accepted pair off the spanning tree): the pairwise
// ICP transforms composed around it, which is the identity for a perfectly consistent loop.
struct LoopReport {
  std::vector<int> scans;   // the cycle's scans in order (the first not repeated)
  double translation = 0;   // m: the composition's translation
  double rotation_deg = 0;  // degrees: the composition's rotation angle
};

struct MultiRegistrationResult {
  std::vector<Rigid3> world_from_scan;  // final poses (start poses for unconnected scans)
  std::vector<ScanReport> scans;
  std::vector<PairReport> pairs;  // every candidate pair, in (moving, fixed) order
  std::vector<LoopReport> loops;
  // Per target: world_from_scan * in_scan - world, m (NaN when its scan is unconnected).
  std::vector<Eigen::Vector3d> target_residuals;
  Rmse control, check;                               // over the targets of connected scans
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // the common origin used, world m
  int outer_iterations = 0;                          // global rounds run
  bool converged = false;  // the last round's poses moved less than the tolerance
  std::string message;     // one line: what happened
};

// `scans[i]` in its own frame (positions: scans[i].frame.ToWorld(p) is the point in scan i's
// frame); `world_from_scan[i]` its start pose. `progress` (optional) gets pairs refined out of
// candidate pairs, then the global rounds.
MultiRegistrationResult RegisterScans(const MultiRegistrationOptions& options,
                                      const std::vector<PointCloud>& scans,
                                      const std::vector<Rigid3>& world_from_scan,
                                      const std::vector<ScanTarget>& targets = {},
                                      const ProgressCallback& progress = nullptr);

}  // namespace candi::photogrammetry

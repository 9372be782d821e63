// Relief panel placement: each panel's world_from_panel from correspondences between points of the
// panel (its corners or edge points, in the panel frame) and their documented positions on the foot
// wall (survey coordinates E, N, H). A robust rigid (default: the panel points are metric) or Sim3
// fit per panel, solved by photogrammetry/georef/similarity_fit.h (Umeyama start, Ceres with a robust loss,
// outlier flags, computed about the centroids so survey coordinates of 10^7 m keep mm detail).
//
// Frames: the panel frame is that of relief_points.h (metres; x along the wall from the panel's
// left edge, y up from its bottom edge, z out of the wall, the wall at z = 0), so a panel of
// width W and height H has the corners (0,0,0), (W,0,0), (W,H,0), (0,H,0). world_from_panel maps
// it to world (survey) coordinates: world = s R panel + t (s = 1 for a rigid fit).
//
// Correspondences CSV (header required; columns in any order, names case-insensitive; '#' lines
// are comments; CsvTable's rules):
//   panel,point,x,y,z,E,N,H[,accuracy]
//   panel     panel id (no commas), e.g. panel_0003; it names the panel's point file <panel>.ply
//   point     name of the point on that panel, unique within the panel, e.g. bottom_left
//   x,y,z     the point in the panel frame, metres
//   E,N,H     its documented position on the wall, metres (easting, northing, height)
//   accuracy  optional 1-sigma accuracy of the documented position, metres, > 0 (weights the fit);
//             an empty field or no column: PanelPlacementOptions::default_accuracy
// Each panel needs at least 3 correspondences, not all at one point.
//
// Per panel the result gives the residuals T * panel - world (mm), their RMS and maximum over the
// correspondences kept in the fit, the outliers flagged (and left out), the layout's collinearity
// and a status: "ok" | "misfit" (RMS above the tolerance, or more outliers than
// max_outlier_fraction: the documented positions do not match the panel's shape, e.g. a panel
// placed in the wrong slot) | "collinear" (the rotation about
// the line of the points is undetermined) | "not converged". Only "ok" panels fit; the others are
// results with warnings, not exceptions.
//
// Failure: a bad file throws InputError "<path>: line N: field '<column>': <what>" (non-numeric or
// non-finite values, empty names, a point named twice on one panel, a bad accuracy, a panel with
// fewer than 3 correspondences or with all of them at one point). Thread-safe (no shared state).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/local_frame.h"
#include "core/transform.h"
#include "reconstruction/photogrammetry/georef/similarity_fit.h"

namespace candi::relief {

struct PanelCorrespondence {
  std::string panel, point;
  Eigen::Vector3d in_panel = Eigen::Vector3d::Zero();  // panel frame, m
  Eigen::Vector3d in_world = Eigen::Vector3d::Zero();  // E, N, H, m
  double accuracy = 0;                                 // m, > 0; 0 = the options' default
  int line = 0;                                        // line in the CSV (0: built in code)
};

// Reads the correspondences CSV (format above). Throws InputError naming path, line and field.
std::vector<PanelCorrespondence> ReadPanelCorrespondences(const std::string& path);
// The same from text, as if read from `path` (for tests and generated tables).
std::vector<PanelCorrespondence> ParsePanelCorrespondences(const std::string& path,
                                                           const std::string& text);

struct PanelPlacementOptions {
  bool estimate_scale = false;   // false: rigid (the panel points are metric); true: Sim3
  photogrammetry::RobustLoss loss = photogrammetry::RobustLoss::kHuber;
  double loss_scale = 0.01;      // m, > 0: residuals beyond this are down-weighted
  double default_accuracy = 0.005;  // m, > 0: for correspondences without an accuracy
  double outlier_k = 4.0;        // > 0: flag residual > k * max(robust sigma, accuracy)
  double tolerance_mm = 20.0;    // > 0: a panel whose RMS residual exceeds this does not fit
  double max_outlier_fraction = 0.25;  // in [0, 1): more outliers than this (and than 1): no fit
  double collinear_ratio = 0.05; // in (0, 1): singular values s2 / s1 below this: collinear
  void Check() const;            // throws std::invalid_argument naming the field
};

struct PanelPlacement {
  std::string panel;
  Sim3 world_from_panel;                      // world = s R panel + t (s = 1 when rigid)
  std::vector<PanelCorrespondence> correspondences;  // in file order
  std::vector<Eigen::Vector3d> residuals_mm;  // T * in_panel - in_world, per correspondence, mm
  std::vector<bool> outlier;                  // flagged and left out of the fit
  int inliers = 0;
  double rms_mm = 0, max_mm = 0;              // over the inliers
  double collinearity = 0, planarity = 0;     // s2 / s1, s3 / s1 of the panel points
  bool converged = false;
  std::string solver_message;
  std::string status;                         // "ok", "misfit", "collinear", "not converged"
  bool fits = false;                          // status == "ok"
  std::vector<std::string> warnings;          // why it does not fit, outliers, solver limits
};

struct PlacementResult {
  std::vector<PanelPlacement> panels;  // in order of each panel's first correspondence
  LocalFrame frame;                    // integer shift of the documented positions (LocalFrame::Auto)
  int misfits = 0;                     // panels that do not fit
};

// Groups the correspondences by panel and fits each. `source` names the file in errors (a panel
// with < 3 correspondences, or coincident panel points: InputError at its first line).
PlacementResult PlacePanels(const PanelPlacementOptions& options,
                            const std::vector<PanelCorrespondence>& correspondences,
                            const std::string& source);

}  // namespace candi::relief

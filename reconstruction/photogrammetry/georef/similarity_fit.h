// Robust similarity (Sim3: scale, rotation, translation) or rigid fit between 3D correspondences:
// target ≈ T * source, e.g. total-station coordinates (E, N, H) from model coordinates.
//
// Method: closed-form weighted Umeyama (S. Umeyama, "Least-squares estimation of transformation
// parameters between two point patterns", PAMI 1991) as the start, then Ceres (Levenberg-Marquardt,
// rotation on ceres::QuaternionManifold, log-scale) minimising sum_i rho(|T x_i - y_i|^2 / a_i^2)
// with a robust loss rho (Huber or Cauchy, scale in metres) and a_i the per-correspondence accuracy.
// Everything is computed about the centroids, so survey coordinates of 10^7 m keep mm detail.
// Outliers: a correspondence whose residual exceeds the threshold (k * max(robust sigma, a_i), the
// robust sigma being 1.4826 * MAD of the residual components; or an absolute threshold in metres)
// is flagged and the fit redone without it, until the flags no longer change.
//
// Degeneracy is reported, not hidden: singular values s1 >= s2 >= s3 of the centred source points
// give collinearity = s2 / s1 (small: the rotation about the line is undetermined) and planarity =
// s3 / s1 (small: the tilt out of the plane, hence the vertical, is weakly determined).
// Non-convergence is a result (converged = false with Ceres' message), not an exception.
// Thread-safe (no shared state).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/transform.h"

namespace candi::photogrammetry {

enum class RobustLoss { kNone, kHuber, kCauchy };
std::string RobustLossName(RobustLoss loss);    // "none", "huber", "cauchy"
RobustLoss ParseRobustLoss(const std::string& name);  // throws std::invalid_argument

struct SimilarityFitOptions {
  bool estimate_scale = true;       // false: rigid fit (scale fixed to 1)
  RobustLoss loss = RobustLoss::kHuber;
  double loss_scale = 0.05;         // m, > 0: residuals beyond this are down-weighted
  double outlier_k = 4.0;           // > 0: flag residual > k * max(robust sigma, accuracy)
  double outlier_threshold = 0.0;   // m, >= 0; > 0 replaces the robust threshold
  bool remove_outliers = true;      // false: flag only, keep every correspondence in the fit
  double collinear_ratio = 0.05;    // in (0, 1): s2 / s1 below this is reported as collinear
  double coplanar_ratio = 0.05;     // in (0, 1): s3 / s1 below this is reported as coplanar
  int max_iterations = 100;         // Ceres iterations per solve, >= 1
  void Check() const;
};

struct SimilarityFitResult {
  Sim3 target_from_source;                 // y = s R x + t, in the caller's (world) coordinates
  std::vector<Eigen::Vector3d> residuals;  // T * x_i - y_i for every correspondence, target units
  std::vector<bool> outlier;               // flagged (excluded from the final fit when removing)
  int inliers = 0;                         // correspondences in the final fit
  double robust_sigma = 0;                 // 1.4826 * MAD of the inliers' residual components
  double threshold = 0;                    // the outlier threshold applied (m; the largest a_i's)
  double collinearity = 0;                 // s2 / s1 of the centred source points (all of them)
  double planarity = 0;                    // s3 / s1
  bool collinear = false, coplanar = false;
  bool converged = false;                  // the last Ceres solve converged
  std::string solver_message;              // Ceres' BriefReport of the last solve
  std::vector<std::string> warnings;       // degeneracy, outlier-removal limits, non-convergence
  double rms = 0;                          // RMS of |residual| over the inliers, m
};

// source, target: #N 3D points (N >= 3, finite); accuracy: #N (> 0, m) or empty (all 1 cm).
// Throws std::invalid_argument for N < 3, mismatched sizes, non-finite values, bad options.
SimilarityFitResult FitSimilarity(const SimilarityFitOptions& options,
                                  const std::vector<Eigen::Vector3d>& source,
                                  const std::vector<Eigen::Vector3d>& target,
                                  const std::vector<double>& accuracy = {});

// Closed-form weighted least squares (Umeyama) about the weighted centroids; weights >= 0, at
// least three positive. Exposed for tests and as a fallback.
Sim3 UmeyamaSimilarity(const std::vector<Eigen::Vector3d>& source,
                       const std::vector<Eigen::Vector3d>& target,
                       const std::vector<double>& weights, bool estimate_scale);

}  // namespace candi::photogrammetry

#include "reconstruction/photogrammetry/georef/similarity_fit.h"

#include <ceres/ceres.h>
#include <ceres/manifold.h>
#include <ceres/rotation.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/check.h"
#include "core/text_format.h"

namespace candi::photogrammetry {

namespace {

constexpr double kDefaultAccuracy = 0.01;  // m, when the caller gives none

// Mean computed as p0 + mean(p - p0): the differences are small, so nothing is lost at 10^7 m.
Eigen::Vector3d Centroid(const std::vector<Eigen::Vector3d>& p, const std::vector<double>& w) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double total = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    sum += w[i] * (p[i] - p[0]);
    total += w[i];
  }
  return p[0] + sum / total;
}

// The fit in local coordinates (about the centroids), mapped back to world coordinates:
// y = s R (x - cx) + t_local + cy  =>  t = t_local + cy - s R cx.
Sim3 ToWorld(const Sim3& local, const Eigen::Vector3d& cx, const Eigen::Vector3d& cy) {
  return Sim3(local.scale, local.rotation,
              local.translation + cy - local.scale * (local.rotation * cx));
}

Eigen::Vector3d SingularValues(const std::vector<Eigen::Vector3d>& p,
                               const std::vector<double>& w) {
  const Eigen::Vector3d c = Centroid(p, w);
  Eigen::MatrixXd design(p.size(), 3);
  for (size_t i = 0; i < p.size(); ++i) design.row(static_cast<Eigen::Index>(i)) = (p[i] - c).transpose();
  return Eigen::JacobiSVD<Eigen::MatrixXd>(design).singularValues();
}

struct PointResidual {
  Eigen::Vector3d x, y;  // local coordinates
  double inv_sigma;
  template <typename T>
  bool operator()(const T* q, const T* t, const T* log_s, T* r) const {
    const T p[3] = {T(x[0]), T(x[1]), T(x[2])};
    T rp[3];
    ceres::UnitQuaternionRotatePoint(q, p, rp);
    const T s = exp(log_s[0]);
    for (int k = 0; k < 3; ++k) r[k] = (s * rp[k] + t[k] - T(y[k])) * T(inv_sigma);
    return true;
  }
  static ceres::CostFunction* Create(const Eigen::Vector3d& x, const Eigen::Vector3d& y,
                                     double inv_sigma) {
    return new ceres::AutoDiffCostFunction<PointResidual, 3, 4, 3, 1>(
        new PointResidual{x, y, inv_sigma});
  }
};

ceres::LossFunction* MakeLoss(RobustLoss loss, double scale) {
  switch (loss) {
    case RobustLoss::kHuber: return new ceres::HuberLoss(scale);
    case RobustLoss::kCauchy: return new ceres::CauchyLoss(scale);
    case RobustLoss::kNone: break;
  }
  return nullptr;
}

struct Solve {
  Sim3 local;  // y_local = s R x_local + t
  bool converged = false;
  std::string message;
};

// Umeyama start, then Ceres on the correspondences with use[i].
Solve SolveLocal(const SimilarityFitOptions& o, const std::vector<Eigen::Vector3d>& x,
                 const std::vector<Eigen::Vector3d>& y, const std::vector<double>& sigma,
                 const std::vector<bool>& use) {
  std::vector<double> w(x.size());
  for (size_t i = 0; i < x.size(); ++i) w[i] = use[i] ? 1.0 / (sigma[i] * sigma[i]) : 0.0;
  const Sim3 start = UmeyamaSimilarity(x, y, w, o.estimate_scale);
  double q[4] = {start.rotation.w(), start.rotation.x(), start.rotation.y(), start.rotation.z()};
  double t[3] = {start.translation.x(), start.translation.y(), start.translation.z()};
  double log_s[1] = {std::log(start.scale)};
  ceres::Problem problem;
  for (size_t i = 0; i < x.size(); ++i) {
    if (!use[i]) continue;
    problem.AddResidualBlock(PointResidual::Create(x[i], y[i], 1.0 / sigma[i]),
                             MakeLoss(o.loss, o.loss_scale / sigma[i]), q, t, log_s);
  }
  problem.SetManifold(q, new ceres::QuaternionManifold);
  if (!o.estimate_scale) problem.SetParameterBlockConstant(log_s);
  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = o.max_iterations;
  solver.function_tolerance = 1e-14;
  solver.gradient_tolerance = 1e-16;
  solver.parameter_tolerance = 1e-14;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  Solve s;
  s.local = Sim3(std::exp(log_s[0]), Eigen::Quaterniond(q[0], q[1], q[2], q[3]),
                 Eigen::Vector3d(t[0], t[1], t[2]));
  s.converged = summary.termination_type == ceres::CONVERGENCE;
  s.message = summary.BriefReport();
  return s;
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  const size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<long>(mid), v.end());
  double m = v[mid];
  if (v.size() % 2 == 0) m = 0.5 * (m + *std::max_element(v.begin(), v.begin() + static_cast<long>(mid)));
  return m;
}

// 1.4826 * MAD of the residual components of the used correspondences.
double RobustSigma(const std::vector<Eigen::Vector3d>& r, const std::vector<bool>& use) {
  std::vector<double> c;
  for (size_t i = 0; i < r.size(); ++i) {
    if (use[i]) c.insert(c.end(), {r[i].x(), r[i].y(), r[i].z()});
  }
  const double m = Median(c);
  for (double& v : c) v = std::abs(v - m);
  return 1.4826 * Median(c);
}

void CheckInputs(const std::vector<Eigen::Vector3d>& source,
                 const std::vector<Eigen::Vector3d>& target, const std::vector<double>& accuracy) {
  if (source.size() != target.size() || (!accuracy.empty() && accuracy.size() != source.size())) {
    throw std::invalid_argument("FitSimilarity: " + std::to_string(source.size()) + " source, " +
                                std::to_string(target.size()) + " target points and " +
                                std::to_string(accuracy.size()) + " accuracies differ in number");
  }
  if (source.size() < 3) {
    throw std::invalid_argument("FitSimilarity: " + std::to_string(source.size()) +
                                " correspondences; a similarity needs at least 3");
  }
  for (size_t i = 0; i < source.size(); ++i) {
    if (!source[i].allFinite() || !target[i].allFinite()) {
      throw std::invalid_argument("FitSimilarity: correspondence " + std::to_string(i) +
                                  " is not finite");
    }
    if (!accuracy.empty() && !(accuracy[i] > 0 && std::isfinite(accuracy[i]))) {
      throw std::invalid_argument("FitSimilarity: accuracy " + std::to_string(i) + " = " +
                                  FormatSignificant(accuracy[i], 3) + "; must be > 0");
    }
  }
}

void ReportDegeneracy(const SimilarityFitOptions& o, const std::vector<Eigen::Vector3d>& source,
                      const std::vector<bool>& use, SimilarityFitResult* r) {
  std::vector<Eigen::Vector3d> p;
  for (size_t i = 0; i < source.size(); ++i) {
    if (use[i]) p.push_back(source[i]);
  }
  const Eigen::Vector3d s = SingularValues(p, std::vector<double>(p.size(), 1.0));
  r->collinearity = s[0] > 0 ? s[1] / s[0] : 0;
  r->planarity = s[0] > 0 ? s[2] / s[0] : 0;
  r->collinear = r->collinearity < o.collinear_ratio;
  r->coplanar = !r->collinear && r->planarity < o.coplanar_ratio;
  if (r->collinear) {
    r->warnings.push_back(
        "targets nearly collinear (s2/s1 = " + FormatSignificant(r->collinearity, 3) + " < " +
        FormatSignificant(o.collinear_ratio, 3) +
        "): the rotation about their line is undetermined or weakly determined");
  } else if (r->coplanar) {
    r->warnings.push_back("targets nearly coplanar (s3/s1 = " + FormatSignificant(r->planarity, 3) +
                          " < " + FormatSignificant(o.coplanar_ratio, 3) +
                          "): the tilt out of their plane (the vertical) and the scale along it "
                          "are weakly determined; points far from the plane extrapolate");
  }
}

}  // namespace

std::string RobustLossName(RobustLoss loss) {
  switch (loss) {
    case RobustLoss::kNone: return "none";
    case RobustLoss::kHuber: return "huber";
    case RobustLoss::kCauchy: return "cauchy";
  }
  return "?";
}

RobustLoss ParseRobustLoss(const std::string& name) {
  for (RobustLoss l : {RobustLoss::kNone, RobustLoss::kHuber, RobustLoss::kCauchy}) {
    if (RobustLossName(l) == name) return l;
  }
  throw std::invalid_argument("loss '" + name + "': must be none, huber or cauchy");
}

void SimilarityFitOptions::Check() const {
  CANDI_CHECK_OPTION(loss_scale > 0 && std::isfinite(loss_scale), loss_scale, "> 0");
  CANDI_CHECK_OPTION(outlier_k > 0 && std::isfinite(outlier_k), outlier_k, "> 0");
  CANDI_CHECK_OPTION(outlier_threshold >= 0 && std::isfinite(outlier_threshold), outlier_threshold,
                     ">= 0");
  CANDI_CHECK_OPTION(collinear_ratio > 0 && collinear_ratio < 1, collinear_ratio, "in (0, 1)");
  CANDI_CHECK_OPTION(coplanar_ratio > 0 && coplanar_ratio < 1, coplanar_ratio, "in (0, 1)");
  CANDI_CHECK_OPTION_GE(max_iterations, 1);
}

Sim3 UmeyamaSimilarity(const std::vector<Eigen::Vector3d>& source,
                       const std::vector<Eigen::Vector3d>& target,
                       const std::vector<double>& weights, bool estimate_scale) {
  const Eigen::Vector3d cx = Centroid(source, weights), cy = Centroid(target, weights);
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  double var_x = 0, total = 0;
  for (size_t i = 0; i < source.size(); ++i) {
    const Eigen::Vector3d dx = source[i] - cx, dy = target[i] - cy;
    cov += weights[i] * dy * dx.transpose();
    var_x += weights[i] * dx.squaredNorm();
    total += weights[i];
  }
  if (!(var_x > 0)) {
    throw std::invalid_argument("FitSimilarity: the source points coincide; no transform is "
                                "determined");
  }
  cov /= total;
  var_x /= total;
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d d = Eigen::Vector3d::Ones();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) d[2] = -1;
  const Eigen::Matrix3d r = svd.matrixU() * d.asDiagonal() * svd.matrixV().transpose();
  const double s = estimate_scale ? svd.singularValues().dot(d) / var_x : 1.0;
  return ToWorld(Sim3(s, Eigen::Quaterniond(r), Eigen::Vector3d::Zero()), cx, cy);
}

SimilarityFitResult FitSimilarity(const SimilarityFitOptions& options,
                                  const std::vector<Eigen::Vector3d>& source,
                                  const std::vector<Eigen::Vector3d>& target,
                                  const std::vector<double>& accuracy) {
  options.Check();
  CheckInputs(source, target, accuracy);
  const size_t n = source.size();
  const std::vector<double> sigma = accuracy.empty() ? std::vector<double>(n, kDefaultAccuracy)
                                                     : accuracy;
  // Local coordinates about the plain centroids.
  const std::vector<double> ones(n, 1.0);
  const Eigen::Vector3d cx = Centroid(source, ones), cy = Centroid(target, ones);
  std::vector<Eigen::Vector3d> x(n), y(n);
  for (size_t i = 0; i < n; ++i) {
    x[i] = source[i] - cx;
    y[i] = target[i] - cy;
  }
  SimilarityFitResult r;
  std::vector<bool> use(n, true);
  constexpr int kMaxRounds = 10;
  for (int round = 0;; ++round) {
    const Solve solve = SolveLocal(options, x, y, sigma, use);
    r.target_from_source = ToWorld(solve.local, cx, cy);
    r.converged = solve.converged;
    r.solver_message = solve.message;
    r.residuals.resize(n);
    for (size_t i = 0; i < n; ++i) r.residuals[i] = solve.local * x[i] - y[i];
    r.robust_sigma = RobustSigma(r.residuals, use);
    std::vector<bool> flag(n);
    size_t flagged = 0;
    r.threshold = 0;
    for (size_t i = 0; i < n; ++i) {
      const double thr = options.outlier_threshold > 0
                             ? options.outlier_threshold
                             : options.outlier_k * std::max(r.robust_sigma, sigma[i]);
      r.threshold = std::max(r.threshold, thr);
      flag[i] = r.residuals[i].norm() > thr;
      flagged += flag[i];
    }
    r.outlier = flag;
    if (!options.remove_outliers) break;
    if (n - flagged < 3 || 2 * flagged > n) {
      r.warnings.push_back(std::to_string(flagged) + " of " + std::to_string(n) +
                           " residuals exceed the outlier threshold; not removed (at least 3 and "
                           "half of the correspondences must remain)");
      break;
    }
    std::vector<bool> keep(n);
    for (size_t i = 0; i < n; ++i) keep[i] = !flag[i];
    if (keep == use) break;
    if (round + 1 == kMaxRounds) {
      r.warnings.push_back("outlier flags still changing after " + std::to_string(kMaxRounds) +
                           " fits");
      break;
    }
    use = keep;
  }
  r.inliers = static_cast<int>(std::count(use.begin(), use.end(), true));
  double sum = 0;
  for (size_t i = 0; i < n; ++i) sum += use[i] ? r.residuals[i].squaredNorm() : 0.0;
  r.rms = std::sqrt(sum / r.inliers);
  ReportDegeneracy(options, source, use, &r);
  if (!r.converged) r.warnings.push_back("the solver did not converge: " + r.solver_message);
  return r;
}

}  // namespace candi::photogrammetry

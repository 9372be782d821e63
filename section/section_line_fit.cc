// The robust local fit of a curve around an anchor point, which the section-line stages use
// (section_lines_internal.h): for the noise (1), the vertices (2) and the ends of the lines (4).
#include "section/section_lines_internal.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace candi::section::lines_internal {

namespace {

// Fits: at most this many iterations and points.
constexpr int kMaxIterations = 30;
constexpr size_t kMaxFitPoints = 24;
// Variance across / along in a window of one curve: (R^2 / 2 r)^2 / 5 over R^2 / 3 for a curve of
// radius r >= 5 R: under 0.005, the start direction needs no search.
constexpr double kOneCurveRatio = 0.005;

Eigen::Vector2d Perp(const Eigen::Vector2d& t) { return Eigen::Vector2d(-t.y(), t.x()); }

// Tukey's biweight of scale tau: (1 - (r / 2.5 tau)^2)^2, like a Gaussian of sigma tau near 0
// (and 0.13 at 2 tau), none beyond 2.5 tau; no exponential to compute. k = 1 / (2.5 tau)^2.
double Biweight(double r, double k) {
  const double v = 1 - k * r * r;
  return v > 0 ? v * v : 0.0;
}
double BiweightFactor(double tau) { return 1 / (6.25 * tau * tau); }

// Principal direction of the points, weighted towards the anchor by (1 - d^2 / R^2)^2, and the
// ratio of the variances across and along it.
Eigen::Vector2d PrincipalDirection(const Window& win, double radius, double* ratio) {
  auto weight = [&](const Eigen::Vector2d& d) {
    const double v = 1 - d.squaredNorm() / (radius * radius);
    return v * v;
  };
  double sum = 0;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const Eigen::Vector2d& d : win.p) {
    sum += weight(d);
    mean += weight(d) * d;
  }
  mean /= sum;
  double sxx = 0, sxy = 0, syy = 0;
  for (const Eigen::Vector2d& d : win.p) {
    const Eigen::Vector2d e = d - mean;
    sxx += weight(d) * e.x() * e.x();
    sxy += weight(d) * e.x() * e.y();
    syy += weight(d) * e.y() * e.y();
  }
  const double angle = 0.5 * std::atan2(2 * sxy, sxx - syy);
  const double mid = 0.5 * (sxx + syy), half = std::hypot(0.5 * (sxx - syy), sxy);
  *ratio = mid + half > 0 ? (mid - half) / (mid + half) : 1.0;
  return Eigen::Vector2d(std::cos(angle), std::sin(angle));
}

// The weight of the points near the line through the anchor along t (biweight of scale tau).
double LineScore(const Window& win, const Eigen::Vector2d& t, double radius, double tau) {
  const Eigen::Vector2d n = Perp(t);
  const double inv_r2 = 1 / (radius * radius), k = BiweightFactor(tau);
  double score = 0;
  for (const Eigen::Vector2d& d : win.p) {
    score += (1 - d.squaredNorm() * inv_r2) * Biweight(n.dot(d), k);
  }
  return score;
}

// Start directions of the fit: of the principal direction (or the hint) and the directions from
// the anchor to up to 8 points of the window, the line through the anchor that holds the most
// weight, and the best one at over 20 degrees from it if that holds over 70 % as much (else
// zero). The principal direction alone points between the arms at a corner or a junction, and
// the fit would settle there; at a corner a line across it through a few points of each arm can
// hold as much weight as the arm itself, and only the fits tell them apart.
std::pair<Eigen::Vector2d, Eigen::Vector2d> StartDirections(const Window& win,
                                                            const Eigen::Vector2d& hint,
                                                            const FitScales& scales) {
  constexpr size_t kCandidates = 8;
  std::vector<std::pair<double, Eigen::Vector2d>> candidates;
  double ratio = 1.0;
  const Eigen::Vector2d base =
      hint.squaredNorm() > 0 ? hint.normalized() : PrincipalDirection(win, scales.radius, &ratio);
  // The points lie along one line or gentle curve (not a corner, a junction or two curves).
  if (ratio < kOneCurveRatio) return {base, Eigen::Vector2d::Zero()};
  candidates.emplace_back(LineScore(win, base, scales.radius, scales.tau_start), base);
  const size_t stride = std::max<size_t>(1, win.size() / kCandidates);
  for (size_t i = 0; i < win.size(); i += stride) {
    const double length = win.p[i].norm();
    if (length < 0.1 * scales.radius) continue;  // too close for a direction
    const Eigen::Vector2d t = win.p[i] / length;
    candidates.emplace_back(LineScore(win, t, scales.radius, scales.tau_start), t);
  }
  size_t best = 0;
  for (size_t k = 1; k < candidates.size(); ++k) {
    if (candidates[k].first > candidates[best].first) best = k;
  }
  const Eigen::Vector2d& t = candidates[best].second;
  size_t second = best;
  for (size_t k = 0; k < candidates.size(); ++k) {
    if (std::abs(candidates[k].second.dot(t)) > 0.94) continue;  // within 20 degrees
    if (second == best || candidates[k].first > candidates[second].first) second = k;
  }
  const bool close = second != best && candidates[second].first > 0.7 * candidates[best].first;
  return {t, close ? candidates[second].second : Eigen::Vector2d::Zero()};
}

// Weighted least squares of y = a + b xi + c xi^2 (xi = x / R) under biweights of scale tau
// about the current coefficients; the quadratic falls back to a line or a constant when the
// weight is too concentrated to fix it (or when `quadratic` is false).
Eigen::Vector3d WeightedFit(const Window& win, const Eigen::Vector3d& coef, double tau,
                            bool quadratic) {
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  double sum = 0;
  int strong = 0;  // points within about 2 tau of the current curve
  const double k = BiweightFactor(tau);
  for (size_t i = 0; i < win.size(); ++i) {
    const Eigen::Vector3d phi(1.0, win.x[i], win.x[i] * win.x[i]);
    const double robust = Biweight(win.y[i] - coef.dot(phi), k);
    const double weight = win.w[i] * robust;
    strong += robust > 0.1;
    m.noalias() += weight * phi * phi.transpose();
    rhs += weight * win.y[i] * phi;
    sum += weight;
  }
  if (!(sum > 0)) return coef;
  Eigen::Vector3d out = Eigen::Vector3d::Zero();
  const double line_det = m(0, 0) * m(1, 1) - m(0, 1) * m(0, 1);
  if (quadratic && strong >= 4 && m.determinant() > 1e-9 * sum * sum * sum) {
    out = m.ldlt().solve(rhs);
  } else if (strong >= 2 && line_det > 1e-9 * sum * sum) {
    out.head<2>() = m.topLeftCorner<2, 2>().ldlt().solve(rhs.head<2>());
  } else {
    out[0] = rhs[0] / sum;
  }
  return out;
}

// A robust noise scale: 1.4826 x the median |residual| of the points within 2 tau of the curve
// (MAD: the points of another arm or curve in the window do not inflate it); 0 if under 3.
double InlierScale(Window* win, const Eigen::Vector3d& coef, double tau) {
  std::vector<double>& r = win->r;
  r.clear();
  for (size_t i = 0; i < win->size(); ++i) {
    const double x = win->x[i];
    const double residual = std::abs(win->y[i] - (coef[0] + (coef[1] + coef[2] * x) * x));
    if (residual < 2 * tau) r.push_back(residual);
  }
  if (r.size() < 3) return 0.0;
  std::nth_element(r.begin(), r.begin() + r.size() / 2, r.end());
  return 1.4826 * r[r.size() / 2];
}

// How far the inliers (sorted x) run on from x = 0 each way without a gap over `gap`: points of
// another curve that happen to lie on this one's extension do not count.
void Reach(const std::vector<double>& x, double gap, double* ahead, double* behind) {
  const size_t zero = std::lower_bound(x.begin(), x.end(), 0.0) - x.begin();
  double end = 0;
  for (size_t i = zero; i < x.size() && x[i] - end <= gap; ++i) end = x[i];
  *ahead = end;
  end = 0;
  for (size_t i = zero; i-- > 0 && end - x[i] <= gap;) end = x[i];
  *behind = -end;
}

// The fit's curve from the coefficients (in xi = x / R), its inliers, support and reach.
void Finish(Window* win, const Eigen::Vector3d& coef, double tau, const FitScales& scales,
            CurveFit* fit) {
  const double r = scales.radius;
  fit->a = coef[0];
  fit->b = coef[1] / r;
  fit->c = coef[2] / (r * r);
  fit->tol = 2 * tau;
  fit->scale = InlierScale(win, coef, tau);
  std::vector<double>& along = win->r;  // the inliers' x, m
  along.clear();
  for (size_t i = 0; i < win->size(); ++i) {
    if (std::abs(fit->Residual(win->p[i])) <= fit->tol) along.push_back(win->x[i] * r);
  }
  fit->support = static_cast<int>(along.size());
  std::sort(along.begin(), along.end());
  Reach(along, scales.gap, &fit->reach_ahead, &fit->reach_behind);
  fit->ok = coef.allFinite() && std::abs(fit->a) <= 0.5 * r && fit->support > 0;
}

// IRLS with a biweight scale that halves (graduated non-convexity): it locks onto the curve
// through the anchor and ignores a parallel one a few scales away. A line first, from tau_start
// to tau_start / 4: a quadratic fitted at a large scale bends to take in points of the other arm
// at a corner. Then the quadratic, down to tau_floor (>= 3 x the noise: about least squares over
// the curve's own points; below the noise the fit would seek a local mode). Adaptive fits stop
// at 3 x the inlier scale instead; they estimate the noise, but at a corner the other arm
// inflates that scale. Inliers: within 2 tau.
CurveFit FitFrom(Window* win, const Eigen::Vector2d& t, const FitScales& scales) {
  CurveFit fit;
  fit.t = t;
  fit.n = Perp(t);
  const double r = scales.radius;
  win->x.resize(win->size());
  win->y.resize(win->size());
  win->w.resize(win->size());
  for (size_t i = 0; i < win->size(); ++i) {
    const Eigen::Vector2d& d = win->p[i];
    win->x[i] = fit.t.dot(d) / r;
    win->y[i] = fit.n.dot(d);
    win->w[i] = 1 - d.squaredNorm() / (r * r);
  }
  Eigen::Vector3d coef = Eigen::Vector3d::Zero();
  double tau = scales.tau_start;
  bool quadratic = false;
  for (int iteration = 0; iteration < kMaxIterations; ++iteration) {
    const Eigen::Vector3d next = WeightedFit(*win, coef, tau, quadratic);
    const double change = (next - coef).cwiseAbs().maxCoeff();
    coef = next;
    const double least = scales.adaptive
                             ? std::max(3 * InlierScale(win, coef, tau), scales.tau_floor)
                             : scales.tau_floor;
    const double next_tau = std::min(tau, std::max(0.5 * tau, least));
    const bool settled = next_tau > 0.9 * tau;  // the scale no longer shrinks
    if (!quadratic) {
      quadratic = settled || next_tau <= 0.25 * scales.tau_start;
    } else if (settled && change <= 1e-3 * tau) {
      break;
    }
    tau = next_tau;
  }
  Finish(win, coef, tau, scales, &fit);
  return fit;
}

}  // namespace

void Gather(const PointGrid& grid, const Eigen::Vector2d& anchor, double radius, Window* win) {
  win->d.clear();
  win->slot.clear();
  const double r2 = radius * radius;
  grid.buckets.ForEachNear(anchor, [&](uint32_t slot) {
    const Eigen::Vector2d d = grid.points[slot] - anchor;
    if (d.squaredNorm() >= r2) return;
    win->d.push_back(d);
    win->slot.push_back(slot);
  });
  win->p.clear();
  const size_t n = win->d.size();
  const size_t used = std::min(n, kMaxFitPoints);
  for (size_t k = 0; k < used; ++k) win->p.push_back(win->d[k * n / used]);
}

// The fit from the best start direction, or from the second one when it is close and its fit
// has more inliers. With a hint, t points along it.
CurveFit FitCurve(Window* win, const Eigen::Vector2d& hint, const FitScales& scales) {
  if (win->size() == 0) return CurveFit();
  auto [first, second] = StartDirections(*win, hint, scales);
  if (hint.squaredNorm() > 0 && first.dot(hint) < 0) first = -first;
  if (hint.squaredNorm() > 0 && second.dot(hint) < 0) second = -second;
  CurveFit fit = FitFrom(win, first, scales);
  if (second.squaredNorm() > 0) {
    CurveFit other = FitFrom(win, second, scales);
    if (other.ok && (!fit.ok || other.support > fit.support)) fit = other;
  }
  return fit;
}

}  // namespace candi::section::lines_internal

#include "mesh/hermite.h"

#include <algorithm>
#include <cmath>

#include "core/check.h"

namespace candi::mesh {

namespace {

bool SameSign(double a, double b) { return (a > 0 && b > 0) || (a < 0 && b < 0); }

// One-sided three-point end tangent, clamped to keep the end interval shape-preserving
// (Moler, "Numerical Computing with MATLAB", pchip).
double EndSlope(double h0, double h1, double d0, double d1) {
  double m = ((2 * h0 + h1) * d0 - h0 * d1) / (h0 + h1);
  if (!SameSign(m, d0)) return 0.0;
  if (!SameSign(d0, d1) && std::abs(m) > 3 * std::abs(d0)) return 3 * d0;
  return m;
}

}  // namespace

MonotoneCubic FitMonotoneCubic(const std::vector<double>& t, const std::vector<double>& value) {
  const size_t n = t.size();
  CANDI_CHECK(n >= 2 && value.size() == n)
      << "FitMonotoneCubic: " << n << " knots, " << value.size() << " values";
  std::vector<double> h(n - 1), d(n - 1);
  for (size_t k = 0; k + 1 < n; ++k) {
    h[k] = t[k + 1] - t[k];
    CANDI_CHECK(h[k] > 0 && std::isfinite(h[k]))
        << "FitMonotoneCubic: knots not increasing at " << k;
    d[k] = (value[k + 1] - value[k]) / h[k];
    CANDI_CHECK(std::isfinite(d[k])) << "FitMonotoneCubic: non-finite value near knot " << k;
  }
  MonotoneCubic c{t, value, std::vector<double>(n, 0.0)};
  if (n == 2) {
    c.slope[0] = c.slope[1] = d[0];
    return c;
  }
  for (size_t k = 1; k + 1 < n; ++k) {
    // A local extremum or a flat neighbour gets a zero tangent; otherwise the weighted harmonic
    // mean of the two slopes, which satisfies the Fritsch-Carlson monotonicity region.
    if (!SameSign(d[k - 1], d[k])) continue;
    const double w1 = 2 * h[k] + h[k - 1], w2 = h[k] + 2 * h[k - 1];
    c.slope[k] = (w1 + w2) / (w1 / d[k - 1] + w2 / d[k]);
  }
  c.slope[0] = EndSlope(h[0], h[1], d[0], d[1]);
  c.slope[n - 1] = EndSlope(h[n - 2], h[n - 3], d[n - 2], d[n - 3]);
  return c;
}

double MonotoneCubic::Evaluate(double x) const {
  if (x <= t.front()) return value.front();
  if (x >= t.back()) return value.back();
  const size_t k = static_cast<size_t>(std::upper_bound(t.begin(), t.end(), x) - t.begin()) - 1;
  const double h = t[k + 1] - t[k], u = (x - t[k]) / h;
  const double u2 = u * u, u3 = u2 * u;
  // v_k + (v_k+1 - v_k) h01 + h (m_k h10 + m_k+1 h11): a flat interval (equal values, zero
  // tangents) returns v_k bit for bit, so vertical segments stay exactly vertical.
  return value[k] + (value[k + 1] - value[k]) * (3 * u2 - 2 * u3) +
         h * (slope[k] * (u3 - 2 * u2 + u) + slope[k + 1] * (u3 - u2));
}

std::vector<Eigen::Vector2d> ResampleByArcLength(const std::vector<Eigen::Vector2d>& vertices,
                                                 int count) {
  CANDI_CHECK(vertices.size() >= 2 && count >= 2)
      << "ResampleByArcLength: " << vertices.size() << " vertices, count " << count;
  std::vector<double> s(vertices.size(), 0.0), x(vertices.size()), y(vertices.size());
  for (size_t k = 0; k < vertices.size(); ++k) {
    if (k > 0) s[k] = s[k - 1] + (vertices[k] - vertices[k - 1]).norm();
    x[k] = vertices[k].x();
    y[k] = vertices[k].y();
  }
  const MonotoneCubic fx = FitMonotoneCubic(s, x), fy = FitMonotoneCubic(s, y);
  std::vector<Eigen::Vector2d> out(static_cast<size_t>(count));
  for (int j = 0; j < count; ++j) {
    const double at = s.back() * j / (count - 1);
    out[static_cast<size_t>(j)] = Eigen::Vector2d(fx.Evaluate(at), fy.Evaluate(at));
  }
  out.front() = vertices.front();
  out.back() = vertices.back();
  return out;
}

}  // namespace candi::mesh

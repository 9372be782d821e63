#include "section/section_lines.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <nanoflann.hpp>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

#include "core/check.h"
#include "core/log.h"
#include "core/rng.h"
#include "core/text_format.h"

namespace candi::section {

namespace {

// Automatic values, as multiples of the typical point gap / of the spacing. 2.5 point gaps per
// vertex keep chords within s^2 / (8 R) = 1.6 mm of a curve of radius R = 20 m at 5 points/m;
// 6 spacings (15 point gaps) is a gap that Poisson sampling leaves by chance once in ~3e6.
constexpr double kSpacingPerPointGap = 2.5;
constexpr double kGapPerSpacing = 6.0;
constexpr double kMinLengthPerSpacing = 2.0;
// Fits: window radius, first and least biweight scale, as multiples of the spacing.
constexpr double kWindowPerSpacing = 3.0;
constexpr double kStartScalePerSpacing = 0.25;
constexpr double kScaleFloorPerSpacing = 0.02;
constexpr int kMaxIterations = 30;
constexpr size_t kMaxFitPoints = 24;
// Variance across / along in a window of one curve: (R^2 / 2 r)^2 / 5 over R^2 / 3 for a curve of
// radius r >= 5 R: under 0.005, the start direction needs no search.
constexpr double kOneCurveRatio = 0.005;
constexpr int kMinSupport = 3;  // inliers of a fit that makes a vertex
// Automatic spacing: k-th neighbour over a sample of the points.
constexpr int kDensityNeighbours = 2;  // few: the k-th is still on the same curve near another
constexpr size_t kDensitySample = size_t{1} << 18;
constexpr size_t kDensityQueries = 2048;
constexpr uint64_t kSampleStream = 0x73656374696f6eULL;  // "section"
// Continuation links: within 15 degrees of the tangent (a chord of length d on a curve of radius
// R turns by d / 2R: R >= 2d; a continuation across to a parallel curve h away needs d >= 3.7 h),
// tangents within 30 degrees; the cost of sideways offsets.
constexpr double kTanNarrow = 0.26794919243112270;    // tan 15 degrees
constexpr double kCosTangents = 0.86602540378443865;  // cos 30 degrees
constexpr double kAcrossPenalty = 4.0;
constexpr uint32_t kNone = std::numeric_limits<uint32_t>::max();
constexpr uint64_t kEmptyKey = ~uint64_t{0};
constexpr int64_t kMaxCells = (int64_t{1} << 31) - 2;  // cells along an axis

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

Eigen::Vector2d Perp(const Eigen::Vector2d& t) { return Eigen::Vector2d(-t.y(), t.x()); }

// ---------------------------------------------------------------------------------------------
// Cells: open addressing with linear probing, cell key -> value. Keys are never kEmptyKey.
class CellTable {
 public:
  // The value stored for `key`, storing `value` first if there is none.
  uint32_t FindOrInsert(uint64_t key, uint32_t value) {
    if (2 * (size_ + 1) > keys_.size()) Grow();
    size_t slot = Slot(key);
    for (; keys_[slot] != kEmptyKey; slot = (slot + 1) & (keys_.size() - 1)) {
      if (keys_[slot] == key) return values_[slot];
    }
    keys_[slot] = key;
    values_[slot] = value;
    ++size_;
    return value;
  }
  // kNone when absent.
  uint32_t Find(uint64_t key) const {
    if (keys_.empty()) return kNone;
    for (size_t slot = Slot(key);; slot = (slot + 1) & (keys_.size() - 1)) {
      if (keys_[slot] == key) return values_[slot];
      if (keys_[slot] == kEmptyKey) return kNone;
    }
  }
  // Replaces every value v by map[v].
  void Renumber(const std::vector<uint32_t>& map) {
    for (size_t slot = 0; slot < keys_.size(); ++slot) {
      if (keys_[slot] != kEmptyKey) values_[slot] = map[values_[slot]];
    }
  }

 private:
  size_t Slot(uint64_t key) const { return Mix64(key) & (keys_.size() - 1); }
  void Grow() {
    std::vector<uint64_t> keys = std::move(keys_);
    std::vector<uint32_t> values = std::move(values_);
    keys_.assign(std::max<size_t>(64, 2 * keys.size()), kEmptyKey);
    values_.assign(keys_.size(), 0);
    size_ = 0;
    for (size_t slot = 0; slot < keys.size(); ++slot) {
      if (keys[slot] != kEmptyKey) FindOrInsert(keys[slot], values[slot]);
    }
  }

  std::vector<uint64_t> keys_;
  std::vector<uint32_t> values_;
  size_t size_ = 0;
};

// Cell indices are offset by one so that the cells around a point at the grid's edge have keys.
uint64_t CellKey(const Eigen::Vector2d& p, double cell, int64_t dx = 0, int64_t dy = 0) {
  auto index = [&](double x, int64_t d) {
    const double i = std::clamp(std::floor(x / cell), -1.0, static_cast<double>(kMaxCells));
    return static_cast<uint64_t>(static_cast<int64_t>(i) + 1 + d);
  };
  return (index(p.x(), dx) << 32) | index(p.y(), dy);
}

// Items bucketed by square cells, cells in key order, items of a cell in index order.
struct Buckets {
  double cell = 1.0;
  CellTable table;              // cell key -> cell rank
  std::vector<uint32_t> start;  // first slot of each cell, by rank; then the end
  std::vector<uint32_t> items;  // item indices, grouped by cell

  // Calls f(slot) for every slot of the 3 x 3 cells around p (a superset of the items within
  // `cell` of p).
  template <typename F>
  void ForEachNear(const Eigen::Vector2d& p, const F& f) const {
    for (int64_t dx = -1; dx <= 1; ++dx) {
      for (int64_t dy = -1; dy <= 1; ++dy) {
        const uint32_t c = table.Find(CellKey(p, cell, dx, dy));
        if (c == kNone) continue;
        for (uint32_t slot = start[c]; slot < start[c + 1]; ++slot) f(slot);
      }
    }
  }
};

// Buckets items 0..n-1 at positions get(i, &p) (false: skip the item).
template <typename Get>
Buckets BuildBuckets(size_t n, double cell, const Get& get) {
  Buckets b;
  b.cell = cell;
  std::vector<uint32_t> cell_of(n, kNone), counts;
  std::vector<uint64_t> keys;
  Eigen::Vector2d p;
  for (size_t i = 0; i < n; ++i) {
    if (!get(i, &p)) continue;
    const uint64_t key = CellKey(p, cell);
    const uint32_t id = b.table.FindOrInsert(key, static_cast<uint32_t>(keys.size()));
    if (id == keys.size()) {
      keys.push_back(key);
      counts.push_back(0);
    }
    ++counts[id];
    cell_of[i] = id;
  }
  std::vector<uint32_t> order(keys.size()), rank(keys.size());
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t x, uint32_t y) { return keys[x] < keys[y]; });
  b.start.assign(keys.size() + 1, 0);
  for (uint32_t r = 0; r < order.size(); ++r) {
    rank[order[r]] = r;
    b.start[r + 1] = b.start[r] + counts[order[r]];
  }
  b.table.Renumber(rank);
  std::vector<uint32_t> cursor(b.start.begin(), b.start.end() - 1);
  b.items.resize(b.start.back());
  for (size_t i = 0; i < n; ++i) {
    if (cell_of[i] != kNone) b.items[cursor[rank[cell_of[i]]]++] = static_cast<uint32_t>(i);
  }
  return b;
}

// The points, relative to the origin, bucketed in cells of the fit window's size; within a cell
// sorted by (u, v), so that the work below does not depend on the input order.
struct PointGrid {
  Buckets buckets;
  std::vector<Eigen::Vector2d> points;  // by slot
};

PointGrid BuildPointGrid(const std::vector<Eigen::Vector2d>& input, const Eigen::Vector2d& origin,
                         double cell) {
  PointGrid grid;
  grid.buckets = BuildBuckets(input.size(), cell, [&](size_t i, Eigen::Vector2d* p) {
    if (!input[i].allFinite()) return false;
    *p = input[i] - origin;
    return true;
  });
  grid.points.resize(grid.buckets.items.size());
  for (size_t k = 0; k < grid.points.size(); ++k) {
    grid.points[k] = input[grid.buckets.items[k]] - origin;
  }
  auto less = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() != b.x() ? a.x() < b.x() : a.y() < b.y();
  };
  const std::vector<uint32_t>& start = grid.buckets.start;
  for (size_t c = 0; c + 1 < start.size(); ++c) {
    std::sort(grid.points.begin() + start[c], grid.points.begin() + start[c + 1], less);
  }
  grid.buckets.items = {};  // input indices: no longer needed
  return grid;
}

// ---------------------------------------------------------------------------------------------
// Automatic spacing.

struct SampleCloud {
  std::vector<Eigen::Vector2d> points;
  size_t kdtree_get_point_count() const { return points.size(); }
  double kdtree_get_pt(uint32_t i, size_t dim) const { return points[i][static_cast<int>(dim)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};
using SampleTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, SampleCloud>,
                                        SampleCloud, 2, uint32_t>;

uint64_t CoordinateHash(const Eigen::Vector2d& p) {
  uint64_t u, v;
  const double x = p.x() + 0.0, y = p.y() + 0.0;  // -0 -> +0
  std::memcpy(&u, &x, sizeof u);
  std::memcpy(&v, &y, sizeof v);
  return Mix64(u ^ Mix64(v ^ kSampleStream));
}

// A sample of the points chosen by a hash of their coordinates (so independent of their order),
// sorted by that hash.
SampleCloud SamplePoints(const std::vector<Eigen::Vector2d>& input, const Eigen::Vector2d& origin,
                         size_t finite) {
  const double fraction = std::min(1.0, static_cast<double>(kDensitySample) / finite);
  std::vector<std::pair<uint64_t, Eigen::Vector2d>> picked;
  for (const Eigen::Vector2d& p : input) {
    if (!p.allFinite()) continue;
    const uint64_t h = CoordinateHash(p);
    if (fraction == 1.0 || ToUnit(h) < fraction) picked.emplace_back(h, p - origin);
  }
  std::sort(picked.begin(), picked.end(), [](const auto& a, const auto& b) {
    if (a.first != b.first) return a.first < b.first;
    return a.second.x() != b.second.x() ? a.second.x() < b.second.x() : a.second.y() < b.second.y();
  });
  SampleCloud sample;
  for (const auto& entry : picked) sample.points.push_back(entry.second);
  return sample;
}

// The typical gap between consecutive points along a curve, m (0 if unknown). k neighbours of a
// point on a curve span about 2 r_k of it; for Poisson sampling at lambda points/m the median of
// r_k is about (k - 1/3) / (2 lambda). A sample of a fraction f of the points has gaps 1/f times
// longer.
double TypicalPointGap(const std::vector<Eigen::Vector2d>& input, const Eigen::Vector2d& origin,
                       size_t finite) {
  const SampleCloud sample = SamplePoints(input, origin, finite);
  const size_t n = sample.points.size();
  if (n < 2) return 0.0;
  const size_t k = std::min<size_t>(kDensityNeighbours, n - 1);
  SampleTree tree(2, sample, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  std::vector<uint32_t> found(k + 1);
  std::vector<double> dist_sq(k + 1), radii;
  for (size_t q = 0; q < std::min(n, kDensityQueries); ++q) {
    const size_t got = tree.knnSearch(sample.points[q].data(), k + 1, found.data(), dist_sq.data());
    if (got == k + 1 && dist_sq[k] > 0) radii.push_back(std::sqrt(dist_sq[k]));
  }
  if (radii.empty()) return 0.0;
  std::nth_element(radii.begin(), radii.begin() + radii.size() / 2, radii.end());
  const double r = radii[radii.size() / 2];
  const double fraction = static_cast<double>(n) / static_cast<double>(finite);
  return 2.0 * r / (static_cast<double>(k) - 1.0 / 3.0) * fraction;
}

// ---------------------------------------------------------------------------------------------
// Local robust fit of the curve around an anchor.

struct FitScales {
  double radius = 1.0;      // window radius R, m
  double tau_start = 0.1;   // first biweight scale, m
  double tau_floor = 0.01;  // least biweight scale, m
  double gap = 0.5;         // the inliers' reach stops at gaps longer than this, m
  bool adaptive = false;    // the scale also stops at 3 x the inlier scale (noise estimation)
};

// The points within R of an anchor, relative to it; the ones the fit uses (all, or an even
// subset of kMaxFitPoints: more add little accuracy and cost time); per-point scratch of the fit.
struct Window {
  std::vector<Eigen::Vector2d> d;
  std::vector<uint32_t> slot;      // in the point grid
  std::vector<Eigen::Vector2d> p;  // the fit's points
  std::vector<double> x, y, w;     // their frame coordinates (x in units of R), spatial weight
  std::vector<double> r;           // scratch
  size_t size() const { return p.size(); }
};

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

// Tukey's biweight of scale tau: (1 - (r / 2.5 tau)^2)^2, like a Gaussian of sigma tau near 0
// (and 0.13 at 2 tau), none beyond 2.5 tau; no exponential to compute. k = 1 / (2.5 tau)^2.
double Biweight(double r, double k) {
  const double v = 1 - k * r * r;
  return v > 0 ? v * v : 0.0;
}
double BiweightFactor(double tau) { return 1 / (6.25 * tau * tau); }

// The curve near the anchor, in the frame (t, n) at the anchor: y = a + b x + c x^2, metres.
struct CurveFit {
  bool ok = false;
  Eigen::Vector2d t = Eigen::Vector2d::UnitX(), n = Eigen::Vector2d::UnitY();
  double a = 0, b = 0, c = 0;
  double tol = 0;                            // inliers lie within tol of the curve, m
  double scale = 0;                          // robust scale of the inliers' residuals, m
  int support = 0;                           // inliers in the window
  double reach_ahead = 0, reach_behind = 0;  // inliers run on this far along +t / -t, m

  Eigen::Vector2d Offset(double x) const { return x * t + (a + (b + c * x) * x) * n; }
  Eigen::Vector2d Tangent(double x) const { return (t + (b + 2 * c * x) * n).normalized(); }
  double Residual(const Eigen::Vector2d& d) const {
    const double x = t.dot(d);
    return n.dot(d) - (a + (b + c * x) * x);
  }
};

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

// ---------------------------------------------------------------------------------------------
// Cover: vertices on the curves.

struct Vertex {
  Eigen::Vector2d p;  // on the curve, relative to the origin
  Eigen::Vector2d t;  // unit tangent
  double reach[2];    // the curve's points seen run on this far along +t and -t, m
};

struct Context {
  PointGrid grid;
  FitScales scales;
  double spacing = 0, max_gap = 0, min_length = 0;
  double noise = 0;  // estimated noise of the points across the curves, m
};

std::vector<Vertex> CoverPoints(const Context& ctx) {
  const std::vector<Eigen::Vector2d>& points = ctx.grid.points;
  const double reach = 0.5 * ctx.spacing;  // covered along the curve each way
  std::vector<uint8_t> covered(points.size(), 0);
  std::vector<Vertex> vertices;
  Window win;
  for (size_t k = 0; k < points.size(); ++k) {
    if (covered[k]) continue;
    covered[k] = 1;
    Gather(ctx.grid, points[k], ctx.scales.radius, &win);
    const CurveFit fit = FitCurve(&win, Eigen::Vector2d::Zero(), ctx.scales);
    // No vertex from an isolated point (noise), a fit that passes the anchor by (a corner cut
    // short) or one through a sixth of the points or less (a chord across a corner).
    const int least = std::max<int>(kMinSupport, static_cast<int>(win.size() / 6) + 1);
    if (!fit.ok || fit.support < least || std::abs(fit.a) > fit.tol) continue;
    for (size_t i = 0; i < win.d.size(); ++i) {
      if (std::abs(fit.t.dot(win.d[i])) <= reach && std::abs(fit.Residual(win.d[i])) <= fit.tol) {
        covered[win.slot[i]] = 1;
      }
    }
    vertices.push_back(
        {points[k] + fit.Offset(0), fit.Tangent(0), {fit.reach_ahead, fit.reach_behind}});
  }
  return vertices;
}

// ---------------------------------------------------------------------------------------------
// Links between vertices.

struct Edge {
  uint32_t a, b;  // a < b
  double length;
};

// Links are searched side by side: side 0 of a vertex is ahead (along +t), side 1 behind.
class Linker {
 public:
  Linker(const std::vector<Vertex>& v, const Context& ctx)
      : v_(v),
        max_gap_(ctx.max_gap),
        search_(ctx.max_gap + 2 * ctx.scales.radius),
        abeam_(0.25 * ctx.spacing),
        buckets_(BuildBuckets(v.size(), search_,
                              [&](size_t i, Eigen::Vector2d* p) {
                                *p = v[i].p;
                                return true;
                              })),
        next_(2 * v.size(), kNone),
        end_(2 * v.size(), kNone) {}

  // First the continuations: each side links to the neighbour within 15 degrees of the tangent
  // (and it within 15 degrees of its own), with a tangent within 30 degrees, of least
  // along + 4 across. Then the ends (sides with none) are matched in pairs, the pairs whose
  // curves end nearest each other first: the two arms of a corner, not the parallel face of a
  // wall nor the middle of a curve.
  std::vector<Edge> Link() {
    for (uint32_t a = 0; a < v_.size(); ++a) Continuations(a);
    MatchEnds();
    std::vector<Edge> edges;
    for (uint32_t a = 0; a < v_.size(); ++a) {
      for (uint32_t side = 2 * a; side < 2 * a + 2; ++side) {
        uint32_t b = next_[side];
        if (b == kNone && end_[side] != kNone) b = end_[side] / 2;
        if (b != kNone)
          edges.push_back({std::min(a, b), std::max(a, b), (v_[b].p - v_[a].p).norm()});
      }
    }
    std::sort(edges.begin(), edges.end(), EdgeLess);
    edges.erase(std::unique(edges.begin(), edges.end(),
                            [](const Edge& x, const Edge& y) { return x.a == y.a && x.b == y.b; }),
                edges.end());
    return edges;
  }

  static bool EdgeLess(const Edge& x, const Edge& y) { return x.a != y.a ? x.a < y.a : x.b < y.b; }

 private:
  // Whether the data gap between a and b, on their sides sa and sb, is at most max_gap.
  bool Near(uint32_t a, int sa, uint32_t b, int sb, double d) const {
    return d > 0 && d <= search_ && d - v_[a].reach[sa] - v_[b].reach[sb] <= max_gap_;
  }

  void Continuations(uint32_t a) {
    double best_cost[2] = {0, 0};
    buckets_.ForEachNear(v_[a].p, [&](uint32_t slot) {
      const uint32_t b = buckets_.items[slot];
      const Eigen::Vector2d rel = v_[b].p - v_[a].p;
      const double along = v_[a].t.dot(rel), across = std::abs(Cross(v_[a].t, rel));
      const int s = along > 0 ? 0 : 1, sb = v_[b].t.dot(rel) < 0 ? 0 : 1;
      if (b == a || !Near(a, s, b, sb, rel.norm())) return;
      // Within the cone of each tangent (a smooth curve's chord makes about the same angle with
      // both), the tangents alike.
      if (across > kTanNarrow * std::abs(along)) return;
      if (std::abs(Cross(v_[b].t, rel)) > kTanNarrow * std::abs(v_[b].t.dot(rel))) return;
      if (std::abs(v_[a].t.dot(v_[b].t)) < kCosTangents) return;
      const double cost = std::abs(along) + kAcrossPenalty * across;
      if (next_[2 * a + s] == kNone || cost < best_cost[s])
        next_[2 * a + s] = b, best_cost[s] = cost;
    });
  }

  // The end side of a (no continuation) that a vertex in direction `toward` may join: the side
  // it lies on, or the other one when it is nearly abeam; -1 if none.
  int EndSide(uint32_t a, const Eigen::Vector2d& toward) const {
    const double along = v_[a].t.dot(toward);
    const int s = along > 0 ? 0 : 1;
    if (next_[2 * a + s] == kNone) return s;
    if (std::abs(along) <= abeam_ && next_[2 * a + 1 - s] == kNone) return 1 - s;
    return -1;
  }

  // Where the curve seen by vertex a ends on side s.
  Eigen::Vector2d ReachEnd(uint32_t a, int s) const {
    return v_[a].p + (s == 0 ? 1.0 : -1.0) * v_[a].reach[s] * v_[a].t;
  }

  struct EndPair {
    double cost;
    uint32_t side_a, side_b;  // side_a < side_b
    bool operator<(const EndPair& o) const {
      if (cost != o.cost) return cost < o.cost;
      return side_a != o.side_a ? side_a < o.side_a : side_b < o.side_b;
    }
  };

  // The end sides that could join a's end sides, with their cost.
  void EndPairs(uint32_t a, std::vector<EndPair>* pairs) const {
    if (next_[2 * a] != kNone && next_[2 * a + 1] != kNone) return;
    buckets_.ForEachNear(v_[a].p, [&](uint32_t slot) {
      const uint32_t b = buckets_.items[slot];
      const Eigen::Vector2d rel = v_[b].p - v_[a].p;
      const int sa = EndSide(a, rel), sb = EndSide(b, -rel);
      if (b <= a || sa < 0 || sb < 0 || !Near(a, sa, b, sb, rel.norm())) return;
      const double cost = (ReachEnd(b, sb) - ReachEnd(a, sa)).norm();
      pairs->push_back({cost, 2 * a + sa, 2 * b + sb});
    });
  }

  // Greedy matching of the end sides, cheapest pair first.
  void MatchEnds() {
    std::vector<EndPair> pairs;
    for (uint32_t a = 0; a < v_.size(); ++a) EndPairs(a, &pairs);
    std::sort(pairs.begin(), pairs.end());
    for (const EndPair& pair : pairs) {
      if (end_[pair.side_a] != kNone || end_[pair.side_b] != kNone) continue;
      end_[pair.side_a] = pair.side_b;
      end_[pair.side_b] = pair.side_a;
    }
  }

  const std::vector<Vertex>& v_;
  double max_gap_, search_, abeam_;
  Buckets buckets_;
  std::vector<uint32_t> next_;  // by side (2 a + s): the continuation vertex, or kNone
  std::vector<uint32_t> end_;   // by end side: the end side matched to it, or kNone
};

bool Linked(const std::vector<Edge>& edges, uint32_t a, uint32_t b) {
  const Edge key{std::min(a, b), std::max(a, b), 0};
  return std::binary_search(edges.begin(), edges.end(), key, Linker::EdgeLess);
}

// ---------------------------------------------------------------------------------------------
// Forest and paths.

struct Forest {
  std::vector<uint32_t> offset, next;  // adjacency (CSR)
  std::vector<uint8_t> alive;
  std::vector<uint32_t> degree;  // alive neighbours
  std::vector<uint8_t> loop;     // the vertex's links hold a cycle (the tree dropped a link)
};

uint32_t Find(std::vector<uint32_t>& parent, uint32_t x) {
  while (parent[x] != x) x = parent[x] = parent[parent[x]];
  return x;
}

// Kruskal: the shortest links that join different trees.
Forest SpanningForest(size_t n, std::vector<Edge> edges) {
  std::sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) {
    if (x.length != y.length) return x.length < y.length;
    return x.a != y.a ? x.a < y.a : x.b < y.b;
  });
  std::vector<uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  std::vector<Edge> kept, dropped;
  for (const Edge& e : edges) {
    const uint32_t ra = Find(parent, e.a), rb = Find(parent, e.b);
    if (ra == rb) {
      dropped.push_back(e);
      continue;
    }
    parent[ra] = rb;
    kept.push_back(e);
  }
  Forest f;
  std::vector<uint8_t> root_loop(n, 0);
  for (const Edge& e : dropped) root_loop[Find(parent, e.a)] = 1;
  f.loop.resize(n);
  for (uint32_t i = 0; i < n; ++i) f.loop[i] = root_loop[Find(parent, i)];
  f.offset.assign(n + 1, 0);
  for (const Edge& e : kept) ++f.offset[e.a + 1], ++f.offset[e.b + 1];
  for (size_t i = 0; i < n; ++i) f.offset[i + 1] += f.offset[i];
  f.next.resize(f.offset[n]);
  std::vector<uint32_t> cursor(f.offset.begin(), f.offset.end() - 1);
  for (const Edge& e : kept) f.next[cursor[e.a]++] = e.b, f.next[cursor[e.b]++] = e.a;
  f.alive.assign(n, 1);
  f.degree.resize(n);
  for (size_t i = 0; i < n; ++i) f.degree[i] = f.offset[i + 1] - f.offset[i];
  return f;
}

// Removes the spurs shorter than min_length: leaf-to-junction chains (a noisy corner or a stub
// of a few vertices), so that the longest paths run through the curves themselves.
void PruneSpurs(const std::vector<Vertex>& v, double min_length, Forest* f) {
  std::vector<uint32_t> chain;
  for (uint32_t leaf = 0; leaf < v.size(); ++leaf) {
    if (!f->alive[leaf] || f->degree[leaf] != 1) continue;
    chain.assign(1, leaf);
    uint32_t prev = kNone, cur = leaf;
    double length = 0;
    while (length < min_length) {
      uint32_t step = kNone;
      for (uint32_t k = f->offset[cur]; k < f->offset[cur + 1]; ++k) {
        if (f->alive[f->next[k]] && f->next[k] != prev) step = f->next[k];
      }
      if (step == kNone || f->degree[step] == 1) break;  // the whole tree is one path
      length += (v[step].p - v[cur].p).norm();
      if (f->degree[step] >= 3) {
        if (length < min_length) {
          for (uint32_t x : chain) f->alive[x] = 0;
          --f->degree[step];
        }
        break;
      }
      chain.push_back(step);
      prev = cur, cur = step;
    }
  }
}

struct PathLine {
  std::vector<uint32_t> ids;
  bool from_junction = false;  // ids[0] is a vertex of an earlier line
};

class PathSplitter {
 public:
  PathSplitter(const std::vector<Vertex>& v, const Forest& f)
      : v_(v), f_(f), used_(v.size(), 0), dist_(v.size(), 0), parent_(v.size(), kNone) {}

  // Each tree: its longest path, then the leftover branches, each from the vertex it hangs on.
  std::vector<PathLine> Split() {
    std::vector<PathLine> lines;
    for (uint32_t s = 0; s < v_.size(); ++s) {
      if (!f_.alive[s] || used_[s]) continue;
      const std::vector<uint32_t> first = LongestFrom(s);
      lines.push_back({LongestFrom(first.back()), false});
      Claim(lines.back().ids);
      while (!tasks_.empty()) {
        const auto [root, start] = tasks_.back();
        tasks_.pop_back();
        if (used_[start]) continue;
        PathLine branch{{root}, true};
        const std::vector<uint32_t> rest = LongestFrom(start);
        branch.ids.insert(branch.ids.end(), rest.begin(), rest.end());
        lines.push_back(std::move(branch));
        Claim(rest);
      }
    }
    return lines;
  }

 private:
  // The path from `start` to the farthest unused vertex of its tree (ties: the lowest index).
  std::vector<uint32_t> LongestFrom(uint32_t start) {
    std::vector<uint32_t> stack{start};
    dist_[start] = 0;
    parent_[start] = kNone;
    uint32_t far = start;
    while (!stack.empty()) {
      const uint32_t x = stack.back();
      stack.pop_back();
      if (dist_[x] > dist_[far] || (dist_[x] == dist_[far] && x < far)) far = x;
      for (uint32_t k = f_.offset[x]; k < f_.offset[x + 1]; ++k) {
        const uint32_t y = f_.next[k];
        if (!f_.alive[y] || used_[y] || y == parent_[x]) continue;
        parent_[y] = x;
        dist_[y] = dist_[x] + (v_[y].p - v_[x].p).norm();
        stack.push_back(y);
      }
    }
    std::vector<uint32_t> path;
    for (uint32_t x = far; x != kNone; x = parent_[x]) path.push_back(x);
    std::reverse(path.begin(), path.end());
    return path;
  }

  void Claim(const std::vector<uint32_t>& path) {
    for (uint32_t x : path) used_[x] = 1;
    for (uint32_t x : path) {
      for (uint32_t k = f_.offset[x]; k < f_.offset[x + 1]; ++k) {
        const uint32_t y = f_.next[k];
        if (f_.alive[y] && !used_[y]) tasks_.emplace_back(x, y);
      }
    }
  }

  const std::vector<Vertex>& v_;
  const Forest& f_;
  std::vector<uint8_t> used_;
  std::vector<double> dist_;
  std::vector<uint32_t> parent_;
  std::vector<std::pair<uint32_t, uint32_t>> tasks_;  // (root on a line, first vertex off it)
};

// ---------------------------------------------------------------------------------------------
// Lines: corners, resampling, ends.

double Length(const std::vector<Eigen::Vector2d>& p, bool closed) {
  double length = 0;
  for (size_t i = 1; i < p.size(); ++i) length += (p[i] - p[i - 1]).norm();
  if (closed && p.size() > 2) length += (p.front() - p.back()).norm();
  return length;
}

// A point of a line: a vertex with its unit tangent, or a corner (tangent zero).
struct Knot {
  Eigen::Vector2d p;
  Eigen::Vector2d t = Eigen::Vector2d::Zero();
};

// The point at fraction f of the segment from a to b: on the cubic Hermite curve through both
// with their tangents (scaled to the chord's length) when both are known and within 30 degrees
// of the chord, else on the chord. Between vertices on a curve, the Hermite curve stays on it
// (to O(h^4) in the spacing h): no refit needed.
Eigen::Vector2d SegmentPoint(const Knot& a, const Knot& b, double f) {
  const Eigen::Vector2d chord = b.p - a.p;
  const double length = chord.norm();
  if (length == 0 || a.t.isZero() || b.t.isZero()) return a.p + f * chord;
  const Eigen::Vector2d ta = a.t.dot(chord) < 0 ? -a.t : a.t;
  const Eigen::Vector2d tb = b.t.dot(chord) < 0 ? -b.t : b.t;
  if (std::min(ta.dot(chord), tb.dot(chord)) < kCosTangents * length) return a.p + f * chord;
  const double f2 = f * f, f3 = f2 * f;
  return (2 * f3 - 3 * f2 + 1) * a.p + (f3 - 2 * f2 + f) * length * ta + (3 * f2 - 2 * f3) * b.p +
         (f3 - f2) * length * tb;
}

double Length(const std::vector<Knot>& k, size_t begin, size_t end) {
  double length = 0;
  for (size_t i = begin; i + 1 < end; ++i) length += (k[i + 1].p - k[i].p).norm();
  return length;
}

// Points from k[begin] to k[end - 1] at equal steps of about `spacing` along the chords, after
// the ones already in *out (the first is not repeated).
void ResamplePiece(const std::vector<Knot>& k, size_t begin, size_t end, double spacing,
                   std::vector<Eigen::Vector2d>* out) {
  const double length = Length(k, begin, end);
  const size_t steps = std::max<size_t>(1, std::lround(length / spacing));
  size_t seg = begin;
  double seg_start = 0;  // length along the chords at k[seg]
  for (size_t step = 1; step < steps; ++step) {
    const double s = length * static_cast<double>(step) / static_cast<double>(steps);
    double seg_length = (k[seg + 1].p - k[seg].p).norm();
    while (seg + 2 < end && seg_start + seg_length < s) {
      seg_start += seg_length;
      ++seg;
      seg_length = (k[seg + 1].p - k[seg].p).norm();
    }
    const double f = seg_length > 0 ? std::clamp((s - seg_start) / seg_length, 0.0, 1.0) : 0.0;
    out->push_back(SegmentPoint(k[seg], k[seg + 1], f));
  }
  out->push_back(k[end - 1].p);
}

// The knots where the line turns by more than 25 degrees (corners): resampling keeps them.
std::vector<size_t> Corners(const std::vector<Knot>& k, bool closed) {
  std::vector<size_t> corners;
  const size_t n = k.size();
  for (size_t i = closed ? 0 : 1; i < (closed ? n : n - 1); ++i) {
    const Eigen::Vector2d in = k[i].p - k[(i + n - 1) % n].p, out = k[(i + 1) % n].p - k[i].p;
    if (in.dot(out) < 0.906 * in.norm() * out.norm()) corners.push_back(i);
  }
  return corners;
}

// Points at equal steps of about `spacing` between the ends and corners of the line (kept). A
// closed line starts at its first corner.
std::vector<Eigen::Vector2d> Resample(std::vector<Knot> ring, bool closed, double spacing) {
  std::vector<size_t> knots = Corners(ring, closed);
  if (closed) {
    const size_t first = knots.empty() ? 0 : knots[0];
    std::rotate(ring.begin(), ring.begin() + first, ring.end());
    for (size_t& k : knots) k -= first;
    ring.push_back(ring.front());
    const double length = Length(ring, 0, ring.size());
    if (knots.empty() && length < 3 * spacing) spacing = length / 3;
  }
  if (knots.empty() || knots.front() != 0) knots.insert(knots.begin(), 0);
  knots.push_back(ring.size() - 1);
  std::vector<Eigen::Vector2d> out(1, ring.front().p);
  for (size_t k = 0; k + 1 < knots.size(); ++k) {
    ResamplePiece(ring, knots[k], knots[k + 1] + 1, spacing, &out);
  }
  if (closed) out.pop_back();  // the first again
  return out;
}

// Extends the end p.back() along the curve to the farthest point the fit there sees beyond it.
void ExtendEnd(const Context& ctx, std::vector<Eigen::Vector2d>* p, Window* win) {
  if (p->size() < 2) return;
  const Eigen::Vector2d end = p->back(), outward = (end - (*p)[p->size() - 2]).normalized();
  Gather(ctx.grid, end, ctx.scales.radius, win);
  const CurveFit fit = FitCurve(win, outward, ctx.scales);
  if (!fit.ok || fit.support < kMinSupport || fit.t.dot(outward) < kCosTangents) return;
  const double reach = fit.reach_ahead;
  if (reach <= 0.1 * ctx.spacing) return;
  const int steps = static_cast<int>(std::ceil(reach / ctx.spacing));
  for (int k = 1; k <= steps; ++k) p->push_back(end + fit.Offset(reach * k / steps));
}

// Open: u increasing from the first vertex to the last (v if equal). Closed: from the vertex of
// least (u, v), counter-clockwise.
void Canonicalize(Polyline2* line) {
  std::vector<Eigen::Vector2d>& p = line->points;
  auto less = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() != b.x() ? a.x() < b.x() : a.y() < b.y();
  };
  if (!line->closed) {
    if (less(p.back(), p.front())) std::reverse(p.begin(), p.end());
    return;
  }
  double area = 0;
  for (size_t i = 0; i < p.size(); ++i) area += Cross(p[i], p[(i + 1) % p.size()]);
  if (area < 0) std::reverse(p.begin(), p.end());
  std::rotate(p.begin(), std::min_element(p.begin(), p.end(), less), p.end());
}

// The corner between consecutive vertices a and b whose tangents differ by over 60 degrees: where
// their tangent lines meet, if the curve each one sees reaches it (within a quarter spacing);
// else false.
bool Corner(const Context& ctx, const Vertex& a, const Vertex& b, Eigen::Vector2d* corner) {
  const double det = Cross(a.t, b.t);
  if (std::abs(a.t.dot(b.t)) >= 0.5 || det == 0) return false;
  const Eigen::Vector2d rel = b.p - a.p;
  const double along_a = Cross(rel, b.t) / det;  // a.p + along_a a.t = b.p + along_b b.t
  const double along_b = Cross(rel, a.t) / det;
  const double slack = 0.25 * ctx.spacing;
  const int side_a = a.t.dot(rel) > 0 ? 0 : 1, side_b = b.t.dot(rel) < 0 ? 0 : 1;
  const double ahead_a = side_a == 0 ? along_a : -along_a,
               ahead_b = side_b == 0 ? along_b : -along_b;
  if (ahead_a < -slack || ahead_a > a.reach[side_a] + slack) return false;
  if (ahead_b < -slack || ahead_b > b.reach[side_b] + slack) return false;
  *corner = a.p + along_a * a.t;
  return true;
}

// The vertices of a path, with the sharp corners between them (see Corner).
std::vector<Knot> PathKnots(const Context& ctx, const std::vector<Vertex>& v,
                            const std::vector<uint32_t>& ids, bool closed) {
  std::vector<Knot> knots;
  Eigen::Vector2d corner;
  for (size_t i = 0; i < ids.size(); ++i) {
    knots.push_back({v[ids[i]].p, v[ids[i]].t});
    const bool last = i + 1 == ids.size();
    if (last && !closed) break;
    if (Corner(ctx, v[ids[i]], v[ids[last ? 0 : i + 1]], &corner)) knots.push_back({corner});
  }
  return knots;
}

Polyline2 MakeLine(const Context& ctx, const std::vector<Vertex>& v, const PathLine& path,
                   bool closed, Window* win) {
  Polyline2 line;
  line.closed = closed;
  line.points = Resample(PathKnots(ctx, v, path.ids, closed), closed, ctx.spacing);
  if (!closed) {
    ExtendEnd(ctx, &line.points, win);
    if (!path.from_junction) {
      std::reverse(line.points.begin(), line.points.end());
      ExtendEnd(ctx, &line.points, win);
    }
  }
  return line;
}

// ---------------------------------------------------------------------------------------------

struct InputSummary {
  size_t finite = 0;
  bool distinct = false;  // at least two different finite points
  Eigen::Vector2d min = Eigen::Vector2d::Zero(), max = Eigen::Vector2d::Zero();
};

InputSummary Summarize(const std::vector<Eigen::Vector2d>& points) {
  InputSummary s;
  for (const Eigen::Vector2d& p : points) {
    if (!p.allFinite()) continue;
    if (s.finite == 0) s.min = s.max = p;
    s.distinct = s.distinct || p != s.min || p != s.max;
    s.min = s.min.cwiseMin(p);
    s.max = s.max.cwiseMax(p);
    ++s.finite;
  }
  return s;
}

// The values used: given ones, else automatic from the typical point gap.
void ResolveScales(const SectionLineOptions& o, const std::vector<Eigen::Vector2d>& points,
                   const InputSummary& in, Context* ctx) {
  if (o.spacing > 0) {
    ctx->spacing = o.spacing;
  } else {
    const double gap = TypicalPointGap(points, in.min, in.finite);
    ctx->spacing = std::max(kSpacingPerPointGap * gap, o.min_spacing);
  }
  ctx->max_gap = o.max_gap > 0 ? o.max_gap : kGapPerSpacing * ctx->spacing;
  ctx->min_length = o.min_length > 0 ? o.min_length : kMinLengthPerSpacing * ctx->spacing;
  ctx->scales.radius = kWindowPerSpacing * ctx->spacing;
  ctx->scales.tau_start = kStartScalePerSpacing * ctx->spacing;
  ctx->scales.tau_floor = kScaleFloorPerSpacing * ctx->spacing;
  ctx->scales.gap = ctx->spacing;
  ctx->scales.adaptive = true;
  const double cells = std::floor((in.max - in.min).maxCoeff() / ctx->scales.radius) + 1;
  if (cells > static_cast<double>(kMaxCells)) {
    throw std::invalid_argument(
        "SectionLineOptions::spacing = " + FormatSignificant(ctx->spacing, 10) +
        (o.spacing > 0 ? "" : " (automatic)") + " makes " + FormatSignificant(cells, 10) +
        " cells along an axis; must be <= 2^31 (pass a larger spacing)");
  }
}

// The noise: the median inlier scale of adaptive fits at up to 256 points spread over the grid.
// The fits' least scale becomes 3 x the noise if that is more than tau_floor.
void AdaptToNoise(Context* ctx) {
  constexpr size_t kSamples = 256;
  const std::vector<Eigen::Vector2d>& points = ctx->grid.points;
  const size_t stride = std::max<size_t>(1, points.size() / kSamples);
  std::vector<double> scales;
  Window win;
  for (size_t k = 0; k < points.size(); k += stride) {
    Gather(ctx->grid, points[k], ctx->scales.radius, &win);
    const CurveFit fit = FitCurve(&win, Eigen::Vector2d::Zero(), ctx->scales);
    if (fit.ok && fit.support >= kMinSupport) scales.push_back(fit.scale);
  }
  ctx->scales.adaptive = false;
  if (scales.empty()) return;
  std::nth_element(scales.begin(), scales.begin() + scales.size() / 2, scales.end());
  ctx->noise = scales[scales.size() / 2];
  ctx->scales.tau_floor = std::max(ctx->scales.tau_floor, 3 * ctx->noise);
  ctx->scales.tau_start = std::max(ctx->scales.tau_start, ctx->scales.tau_floor);
}

// The lines of the forest's paths, in the output frame and order (the file comment).
std::vector<Polyline2> BuildLines(const Context& ctx, const std::vector<Vertex>& vertices,
                                  const std::vector<Edge>& edges, const Forest& forest,
                                  const Eigen::Vector2d& origin) {
  std::vector<std::pair<double, Polyline2>> lines;  // with their lengths
  Window win;
  for (const PathLine& path : PathSplitter(vertices, forest).Split()) {
    if (path.ids.size() < 2) continue;
    // A loop: the ends are linked, or near and their links hold a cycle (a spur at the join).
    const uint32_t first = path.ids.front(), last = path.ids.back();
    const bool closed =
        !path.from_junction && path.ids.size() >= 3 &&
        (Linked(edges, first, last) ||
         (forest.loop[first] && (vertices[first].p - vertices[last].p).norm() <= ctx.max_gap));
    Polyline2 line = MakeLine(ctx, vertices, path, closed, &win);
    const double length = Length(line.points, line.closed);
    if (length < ctx.min_length) continue;
    for (Eigen::Vector2d& p : line.points) p += origin;
    Canonicalize(&line);
    lines.emplace_back(length, std::move(line));
  }
  std::stable_sort(lines.begin(), lines.end(), [](const auto& a, const auto& b) {
    if (a.first != b.first) return a.first > b.first;
    const Eigen::Vector2d &pa = a.second.points.front(), &pb = b.second.points.front();
    return pa.x() != pb.x() ? pa.x() < pb.x() : pa.y() < pb.y();
  });
  std::vector<Polyline2> out;
  for (auto& entry : lines) out.push_back(std::move(entry.second));
  return out;
}

}  // namespace

void SectionLineOptions::Check() const {
  CANDI_CHECK_OPTION(spacing >= 0 && std::isfinite(spacing), spacing,
                     "finite and >= 0 (0 = automatic)");
  CANDI_CHECK_OPTION(max_gap >= 0 && std::isfinite(max_gap), max_gap,
                     "finite and >= 0 (0 = automatic)");
  CANDI_CHECK_OPTION(min_length >= 0 && std::isfinite(min_length), min_length,
                     "finite and >= 0 (0 = automatic)");
  CANDI_CHECK_OPTION(min_spacing > 0 && std::isfinite(min_spacing), min_spacing, "finite and > 0");
}

SectionLines ExtractSectionLines(const SectionLineOptions& options,
                                 const std::vector<Eigen::Vector2d>& points) {
  options.Check();
  SectionLines result;
  const InputSummary in = Summarize(points);
  result.points = in.finite;
  if (!in.distinct) return result;
  CANDI_CHECK(in.finite < kNone) << "ExtractSectionLines: " << in.finite
                                 << " points; at most 2^32-2";
  Context ctx;
  ResolveScales(options, points, in, &ctx);
  result.spacing = ctx.spacing;
  result.max_gap = ctx.max_gap;
  result.min_length = ctx.min_length;
  ctx.grid = BuildPointGrid(points, in.min, ctx.scales.radius);
  AdaptToNoise(&ctx);
  const std::vector<Vertex> vertices = CoverPoints(ctx);
  const std::vector<Edge> edges = Linker(vertices, ctx).Link();
  Forest forest = SpanningForest(vertices.size(), edges);
  PruneSpurs(vertices, ctx.min_length, &forest);
  result.lines = BuildLines(ctx, vertices, edges, forest, in.min);
  LogDebug("section lines: " + std::to_string(in.finite) + " points, " +
           std::to_string(vertices.size()) + " vertices, " + std::to_string(result.lines.size()) +
           " lines, spacing " + FormatSignificant(ctx.spacing, 10) + " m, max gap " +
           FormatSignificant(ctx.max_gap, 10) + " m, noise " + FormatSignificant(ctx.noise, 10) +
           " m");
  return result;
}

}  // namespace candi::section

#include "reconstruction/photogrammetry/mvs/patch_match.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <exception>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <tbb/blocked_range.h>
#include <tbb/task_arena.h>

#include "core/check.h"
#include "core/parallel.h"
#include "core/rng.h"
#include "core/simd.h"

namespace candi::photogrammetry {

namespace {

constexpr double kPi = 3.14159265358979323846;

Image8 ToRgb(const Image8& in) {
  if (in.channels() == 3) return in;
  Image8 out(in.width(), in.height(), 3);
  for (int y = 0; y < in.height(); ++y)
    for (int x = 0; x < in.width(); ++x)
      for (int c = 0; c < 3; ++c) out.at(x, y, c) = in.at(x, y, in.channels() == 1 ? 0 : c);
  return out;
}

}  // namespace

StereoView PrepareStereoView(const StereoImage& in, double scale) {
  CANDI_CHECK(in.camera.Valid() && in.camera.rotation.allFinite() && in.camera.translation.allFinite() &&
              std::isfinite(in.camera.cx) && std::isfinite(in.camera.cy))
      << in.name << ": invalid camera";
  CANDI_CHECK(in.image.width() == in.camera.width && in.image.height() == in.camera.height)
      << in.name << ": image " << in.image.width() << "x" << in.image.height() << " vs camera "
      << in.camera.width << "x" << in.camera.height;
  StereoView v;
  v.camera = scale == 1.0 ? in.camera : in.camera.Scaled(scale);
  const Image8 rgb = ToRgb(in.image);
  v.color = scale == 1.0 ? rgb : ResampleArea(rgb, v.camera.width, v.camera.height);
  v.grey.resize(static_cast<size_t>(v.color.width()) * v.color.height());
  for (int y = 0; y < v.color.height(); ++y)
    for (int x = 0; x < v.color.width(); ++x)
      v.grey[static_cast<size_t>(y) * v.color.width() + x] = static_cast<float>(
          (0.299 * v.color.at(x, y, 0) + 0.587 * v.color.at(x, y, 1) + 0.114 * v.color.at(x, y, 2)) / 255.0);
  v.K << v.camera.fx, 0, v.camera.cx, 0, v.camera.fy, v.camera.cy, 0, 0, 1;
  v.K_inv = v.K.inverse();
  return v;
}

size_t StereoView::Bytes() const {
  return color.values().size() + grey.size() * sizeof(float) + sizeof(StereoView);
}


std::pair<double, double> StereoDepthRange(const PatchMatchOptions& o, const PinholeCamera& cam,
                                     const std::vector<Eigen::Vector3d>& points) {
  if (o.depth_min > 0 && o.depth_max > 0) return {o.depth_min, o.depth_max};
  std::vector<double> inside, front;
  for (const Eigen::Vector3d& p : points) {
    const Eigen::Vector3d c = cam.ToCamera(p);
    if (!(c.z() > 0) || !std::isfinite(c.z())) continue;
    front.push_back(c.z());
    const Eigen::Vector2d uv = cam.Project(c);
    if (uv.x() >= 0 && uv.y() >= 0 && uv.x() < cam.width && uv.y() < cam.height) inside.push_back(c.z());
  }
  std::vector<double>& d = inside.size() >= 8 ? inside : front;
  if (d.empty())
    throw std::invalid_argument("PatchMatchOptions: no depth range (set depth_min and depth_max, or "
                                "give sparse points in front of the cameras)");
  std::sort(d.begin(), d.end());
  const double lo = d[static_cast<size_t>(0.02 * (d.size() - 1))];
  const double hi = d[static_cast<size_t>(0.98 * (d.size() - 1))];
  return {0.75 * lo, 1.25 * hi};
}

namespace {

struct Plane {
  double depth = 0;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
};

// The reference window of one pixel: sample offsets, weights and values, weighted mean/variance.
// The arrays are padded to a multiple of kLanes with copies of the first sample at weight 0, so
// the cost kernel runs whole vectors and the padding changes neither a sum nor the visibility.
constexpr size_t kLanes = 8;
struct RefWindow {
  std::vector<float> u, v;  // sample pixel centres in the reference image
  std::vector<float> weight, value;
  double mean = 0, var = 0;
};

// Weighted sums of the source samples of one window under a homography (sum w, w s, w s^2,
// w s r; s source grey, r reference grey). False when a sample is behind the source camera or
// outside its image. Eight lanes in GCC vector types, compiled for AVX2 and for the baseline: both
// give the same bits (lane-wise IEEE operations, no FMA contraction, a fixed reduction order).
typedef float V8f __attribute__((vector_size(32)));
typedef int32_t V8i __attribute__((vector_size(32)));

CANDI_TARGET_CLONES_AVX2
bool WindowSums(const float* hm, const float* us_in, const float* vs_in, const float* weights,
                const float* values, size_t n, const float* grey, int width, int height, double out[4]) {
  const V8f h0 = V8f{} + hm[0], h1 = V8f{} + hm[1], h2 = V8f{} + hm[2], h3 = V8f{} + hm[3];
  const V8f h4 = V8f{} + hm[4], h5 = V8f{} + hm[5], h6 = V8f{} + hm[6], h7 = V8f{} + hm[7];
  const V8f h8 = V8f{} + hm[8];
  const V8f wmax = V8f{} + static_cast<float>(width - 1), hmax = V8f{} + static_cast<float>(height - 1);
  const V8f zero = V8f{}, half = V8f{} + 0.5f, one = V8f{} + 1.0f;
  V8f sw = zero, s1 = zero, s2 = zero, s12 = zero;
  for (size_t i = 0; i < n; i += kLanes) {
    V8f u, v, wt, r;
    std::memcpy(&u, us_in + i, sizeof(u));
    std::memcpy(&v, vs_in + i, sizeof(v));
    std::memcpy(&wt, weights + i, sizeof(wt));
    std::memcpy(&r, values + i, sizeof(r));
    const V8f hz = h6 * u + h7 * v + h8;
    const V8f inv = one / hz;
    const V8f su = (h0 * u + h1 * v + h2) * inv - half;
    const V8f sv = (h3 * u + h4 * v + h5) * inv - half;
    // NaN fails every comparison, so it counts as outside.
    const V8i ok = (hz > zero) & (su >= zero) & (sv >= zero) & (su < wmax) & (sv < hmax);
    int all = -1;
    for (size_t l = 0; l < kLanes; ++l) all &= ok[l];
    if (!all) return false;
    const V8i ix = __builtin_convertvector(su, V8i), iy = __builtin_convertvector(sv, V8i);
    const V8f fx = su - __builtin_convertvector(ix, V8f), fy = sv - __builtin_convertvector(iy, V8f);
    const V8i at = iy * width + ix;
    V8f a, b, c, d;
    for (size_t l = 0; l < kLanes; ++l) {
      const float* p = grey + at[l];
      a[l] = p[0], b[l] = p[1], c[l] = p[width], d[l] = p[width + 1];
    }
    const V8f s = (one - fy) * ((one - fx) * a + fx * b) + fy * ((one - fx) * c + fx * d);
    sw += wt, s1 += wt * s, s2 += wt * s * s, s12 += wt * s * r;
  }
  for (int k = 0; k < 4; ++k) out[k] = 0;
  for (size_t l = 0; l < kLanes; ++l) out[0] += sw[l], out[1] += s1[l], out[2] += s2[l], out[3] += s12[l];
  return true;
}

class ReferenceMatcher {
 public:
  ReferenceMatcher(const PatchMatchOptions& o, const StereoView& ref, int ref_index,
                   std::vector<const StereoView*> sources, std::vector<int> source_indices, double dmin, double dmax)
      : o_(o), sources_(std::move(sources)), ref_(ref), ref_index_(ref_index),
        source_indices_(std::move(source_indices)), dmin_(dmin), dmax_(dmax) {
    const int w = ref_.camera.width, h = ref_.camera.height;
    planes_.assign(static_cast<size_t>(w) * h, Plane());
    cost_.assign(planes_.size(), 2.0f);
    for (const StereoView* s : sources_) {
      const PinholeCamera& src = s->camera;
      const Eigen::Matrix3d R = src.rotation * ref_.camera.rotation.transpose();
      // The plane-induced homography K_s (R + t n^T / rho) K_r^-1 = A + B m^T with m = K_r^-T n / rho.
      A_.push_back(s->K * R * ref_.K_inv);
      B_.push_back(s->K * (src.translation - R * ref_.camera.translation));
    }
    const double sigma_s = o_.bilateral_sigma_spatial > 0 ? o_.bilateral_sigma_spatial : o_.window_radius;
    for (int y = -o_.window_radius; y <= o_.window_radius; y += o_.window_step) {
      for (int x = -o_.window_radius; x <= o_.window_radius; x += o_.window_step) {
        offsets_x_.push_back(x);
        offsets_y_.push_back(y);
        spatial_.push_back(std::exp(-(x * x + y * y) / (2 * sigma_s * sigma_s)));
      }
    }
    best_ = std::max<int>(1, (static_cast<int>(sources_.size()) + 1) / 2);
  }

  bool HasSources() const { return !sources_.empty(); }

  uint64_t Stream(int round, int colour, int k) const {
    return ((static_cast<uint64_t>(ref_index_) * 64 + round) * 2 + colour) * 16 + k;
  }

  // Random plane for pixel (x, y): inverse depth uniform, normal uniform on the visible hemisphere.
  Plane RandomPlane(int x, int y, uint64_t pixel, uint64_t stream) const {
    Plane p;
    const double u = ToUnit(HashIndex(o_.seed, pixel, stream));
    p.depth = 1.0 / (1.0 / dmax_ + u * (1.0 / dmin_ - 1.0 / dmax_));
    p.normal = RandomNormal(x, y, pixel, stream + 1000003, 1.0, Eigen::Vector3d::Zero());
    return p;
  }

  // A unit normal facing the camera: `base` + `spread` * a random unit vector (base zero: uniform).
  Eigen::Vector3d RandomNormal(int x, int y, uint64_t pixel, uint64_t stream, double spread,
                               const Eigen::Vector3d& base) const {
    const double z = 2 * ToUnit(HashIndex(o_.seed, pixel, stream)) - 1;
    const double phi = 2 * kPi * ToUnit(HashIndex(o_.seed, pixel, stream + 7919));
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    Eigen::Vector3d n = base + spread * Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
    if (n.squaredNorm() < 1e-12) n = Eigen::Vector3d(0, 0, -1);
    n.normalize();
    const Eigen::Vector3d ray = ref_.camera.Ray(x + 0.5, y + 0.5).normalized();
    if (n.dot(ray) > 0) n = -n;
    if (n.dot(ray) > -0.1) n = (n - (n.dot(ray) + 0.1) * ray).normalized();  // not grazing
    return n;
  }

  bool BuildWindow(int x, int y, RefWindow* win) const {
    const int w = ref_.camera.width, h = ref_.camera.height;
    const double centre = ref_.grey[static_cast<size_t>(y) * w + x];
    const double sc = o_.bilateral_sigma_color;
    win->u.clear(), win->v.clear(), win->weight.clear(), win->value.clear();
    double sw = 0, s1 = 0, s2 = 0;
    for (size_t i = 0; i < spatial_.size(); ++i) {
      const int qx = x + offsets_x_[i], qy = y + offsets_y_[i];
      if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
      const double v = ref_.grey[static_cast<size_t>(qy) * w + qx];
      double wt = spatial_[i];
      if (sc > 0) wt *= std::exp(-(v - centre) * (v - centre) / (2 * sc * sc));
      win->u.push_back(static_cast<float>(qx + 0.5)), win->v.push_back(static_cast<float>(qy + 0.5));
      win->weight.push_back(static_cast<float>(wt)), win->value.push_back(static_cast<float>(v));
      sw += wt, s1 += wt * v, s2 += wt * v * v;
    }
    if (sw <= 0) return false;
    while (win->u.size() % kLanes != 0) {
      win->u.push_back(win->u[0]), win->v.push_back(win->v[0]);
      win->weight.push_back(0.0f), win->value.push_back(0.0f);
    }
    win->mean = s1 / sw;
    win->var = std::max(0.0, s2 / sw - win->mean * win->mean);
    return std::sqrt(win->var) >= o_.min_texture && win->var > 1e-8;
  }

  // 1 - NCC of the window against one source under the plane's homography hm (row-major); 2 when
  // not visible.
  // Float arithmetic: image coordinates stay below 2^14, where float keeps 1e-3 px.
  double SourceCost(int k, const RefWindow& win, const float hm[9]) const {
    const StereoView& src = *sources_[k];
    double sums[4];
    if (!WindowSums(hm, win.u.data(), win.v.data(), win.weight.data(), win.value.data(), win.u.size(),
                    src.grey.data(), src.camera.width, src.camera.height, sums))
      return 2.0;
    const double sw = sums[0], ms = sums[1] / sw, vs = sums[2] / sw - ms * ms;
    if (vs < 1e-6) return 2.0;  // a flat source window (float noise below this)
    const double ncc = (sums[3] / sw - ms * win.mean) / std::sqrt(vs * win.var);
    return std::clamp(1.0 - ncc, 0.0, 2.0);
  }

  double Cost(int x, int y, const RefWindow& win, const Plane& p) const {
    if (!(p.depth >= dmin_ && p.depth <= dmax_)) return 2.0;
    const Eigen::Vector3d X0 = p.depth * ref_.camera.Ray(x + 0.5, y + 0.5);
    const double rho = p.normal.dot(X0);
    if (!(std::abs(rho) > 1e-12)) return 2.0;
    double costs[32];
    const int n = static_cast<int>(sources_.size());
    const Eigen::Vector3d m = ref_.K_inv.transpose() * p.normal / rho;
    for (int k = 0; k < n; ++k) {
      float h[9];
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) h[3 * r + c] = static_cast<float>(A_[k](r, c) + B_[k][r] * m[c]);
      costs[k] = SourceCost(k, win, h);
    }
    std::partial_sort(costs, costs + best_, costs + n);
    double sum = 0;
    for (int k = 0; k < best_; ++k) sum += costs[k];
    return sum / best_;
  }

  void Initialise(int y, RefWindow* win) {
    const int w = ref_.camera.width;
    for (int x = 0; x < w; ++x) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (!BuildWindow(x, y, win)) {
        planes_[i] = Plane();
        cost_[i] = 2.0f;
        continue;
      }
      planes_[i] = RandomPlane(x, y, i, Stream(63, 0, 0));
      cost_[i] = static_cast<float>(Cost(x, y, *win, planes_[i]));
    }
  }

  // Propagation from the other colour, then refinement, for the pixels of `colour` in row y.
  void SweepRow(int y, int round, int colour, RefWindow* win) {
    static const int kNx[8] = {-1, 1, 0, 0, -5, 5, 0, 0};
    static const int kNy[8] = {0, 0, -1, 1, 0, 0, -5, 5};
    const int w = ref_.camera.width, h = ref_.camera.height;
    for (int x = (y + colour) & 1; x < w; x += 2) {
      const size_t i = static_cast<size_t>(y) * w + x;
      if (planes_[i].depth <= 0 || !BuildWindow(x, y, win)) continue;
      Plane best = planes_[i];
      double best_cost = cost_[i];
      auto Try = [&](const Plane& p) {
        const double c = Cost(x, y, *win, p);
        if (c < best_cost) best_cost = c, best = p;
      };
      // Propagation copies planes, so neighbours often carry this pixel's plane or each other's:
      // each distinct plane is costed once (costing a repeat again could not change the plane kept).
      const Plane* seen[9] = {&planes_[i]};
      int n_seen = 1;
      for (int k = 0; k < 8; ++k) {
        const int qx = x + kNx[k], qy = y + kNy[k];
        if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
        const Plane& q = planes_[static_cast<size_t>(qy) * w + qx];
        if (!(q.depth > 0)) continue;
        bool repeat = false;
        for (int j = 0; j < n_seen && !repeat; ++j)
          repeat = seen[j]->depth == q.depth && seen[j]->normal == q.normal;
        if (repeat) continue;
        seen[n_seen++] = &q;
        Try(q);
      }
      // Refinement: perturbations shrinking with the round, plus fresh random depth and normal.
      const double spread = 0.5 * std::pow(0.5, round);
      const double span = (dmax_ - dmin_) * 0.1 * std::pow(0.5, round);
      const uint64_t s = Stream(round, colour, 0);
      const Plane cur = best;
      const Plane random = RandomPlane(x, y, i, s);
      Plane pd = cur, pn = cur, pdn = cur, rd = cur, rn = cur;
      pd.depth = cur.depth + span * (2 * ToUnit(HashIndex(o_.seed, i, s + 2)) - 1);
      pn.normal = RandomNormal(x, y, i, s + 3, spread, cur.normal);
      pdn.depth = pd.depth, pdn.normal = pn.normal;
      rd.depth = random.depth;
      rn.normal = random.normal;
      for (const Plane& p : {random, pd, pn, pdn, rd, rn}) Try(p);
      planes_[i] = best;
      cost_[i] = static_cast<float>(best_cost);
    }
  }

  DepthNormalMap Result() const {
    DepthNormalMap m;
    m.camera = ref_.camera;
    const int w = m.camera.width, h = m.camera.height;
    m.depth = ImageF(w, h, 1, 0.0f);
    m.normal = ImageF(w, h, 3, 0.0f);
    m.cost = ImageF(w, h, 1, 2.0f);
    m.color = ref_.color;
    m.source_views = source_indices_;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const Plane& p = planes_[static_cast<size_t>(y) * w + x];
        if (!(p.depth > 0)) continue;
        m.depth.at(x, y) = static_cast<float>(p.depth);
        for (int c = 0; c < 3; ++c) m.normal.at(x, y, c) = static_cast<float>(p.normal[c]);
        m.cost.at(x, y) = cost_[static_cast<size_t>(y) * w + x];
      }
    }
    return m;
  }

 private:
  const PatchMatchOptions& o_;
  std::vector<const StereoView*> sources_;
  const StereoView& ref_;
  int ref_index_;
  std::vector<int> source_indices_;
  double dmin_, dmax_;
  std::vector<Eigen::Matrix3d> A_;
  std::vector<Eigen::Vector3d> B_;
  std::vector<int> offsets_x_, offsets_y_;
  std::vector<double> spatial_;
  int best_ = 1;
  std::vector<Plane> planes_;
  std::vector<float> cost_;
};

// Runs f(y) for every row, in parallel; f must only write row y's state.
template <typename F>
void ForRows(int height, const F& f) {
  ParallelFor(tbb::blocked_range<int>(0, height, 4), [&](const tbb::blocked_range<int>& r) {
    RefWindow win;
    for (int y = r.begin(); y < r.end(); ++y) f(y, &win);
  });
}

}  // namespace

Image8 ResampleArea(const Image8& rgb, int width, int height) {
  CANDI_CHECK(rgb.channels() == 3 && width > 0 && height > 0) << "ResampleArea: RGB to a positive size";
  const cv::Mat src(rgb.height(), rgb.width(), CV_8UC3, const_cast<uint8_t*>(rgb.data()));
  Image8 out(width, height, 3);
  cv::Mat dst(height, width, CV_8UC3, out.data());
  cv::resize(src, dst, dst.size(), 0, 0, cv::INTER_AREA);
  return out;
}

void PatchMatchOptions::Check() const {
  CANDI_CHECK_OPTION_IN(window_radius, 1, 15);
  CANDI_CHECK_OPTION_IN(window_step, 1, window_radius);
  CANDI_CHECK_OPTION_IN(iterations, 1, 50);
  CANDI_CHECK_OPTION_IN(num_source_views, 1, 32);
  CANDI_CHECK_OPTION_IN(num_check_views, num_source_views, 64);
  CANDI_CHECK_OPTION(resolution_scale > 0 && resolution_scale <= 1, resolution_scale, "in (0, 1]");
  // The rule names depth_min when the range is set and depth_min is not > 0, else depth_max.
  const bool range_set = depth_min != 0 || depth_max != 0;
  const bool range_ok = std::isfinite(depth_min) && std::isfinite(depth_max) &&
                        (!range_set || (depth_min > 0 && depth_max > depth_min));
  const char* range_rule = "both 0 (from the data) or 0 < depth_min < depth_max";
  CANDI_CHECK_OPTION(range_ok || !(range_set && !(depth_min > 0)), depth_min, range_rule);
  CANDI_CHECK_OPTION(range_ok, depth_max, range_rule);
  CANDI_CHECK_OPTION(min_triangulation_angle_deg >= 0 && min_triangulation_angle_deg < 60,
                     min_triangulation_angle_deg, "in [0, 60)");
  CANDI_CHECK_OPTION_GE(bilateral_sigma_color, 0);
  CANDI_CHECK_OPTION_GE(bilateral_sigma_spatial, 0);
  CANDI_CHECK_OPTION_GE(min_texture, 0);
  CANDI_CHECK_OPTION(max_cost > 0 && max_cost <= 2, max_cost, "in (0, 2]");
  CANDI_CHECK_OPTION_GT(max_reprojection_error_px, 0);
  CANDI_CHECK_OPTION_GT(max_depth_error, 0);
  CANDI_CHECK_OPTION_IN(min_consistent_views, 0, 32);
  CANDI_CHECK_OPTION_GE(threads, 0);
  Sources().Check();
}

DepthNormalMap MatchReference(const PatchMatchOptions& o, const StereoView& ref, int ref_index,
                              const std::vector<const StereoView*>& sources, const std::vector<int>& source_indices,
                              std::pair<double, double> depth_range, const std::function<void(uint64_t)>& swept) {
  CANDI_CHECK(sources.size() == source_indices.size()) << sources.size() << " vs " << source_indices.size();
  const auto [dmin, dmax] = depth_range;
  ReferenceMatcher m(o, ref, ref_index, sources, source_indices, dmin, dmax);
  const int h = ref.camera.height;
  const uint64_t pixels = static_cast<uint64_t>(ref.camera.width) * h;
  if (!m.HasSources()) {
    if (swept) swept(pixels * (2 * o.iterations + 1));
    return m.Result();  // every plane unset: no depth
  }
  ForRows(h, [&](int y, RefWindow* win) { m.Initialise(y, win); });
  if (swept) swept(pixels);
  for (int round = 0; round < o.iterations; ++round) {
    for (int colour = 0; colour < 2; ++colour) {
      ForRows(h, [&](int y, RefWindow* win) { m.SweepRow(y, round, colour, win); });
      if (swept) swept(pixels);
    }
  }
  return m.Result();
}

void FilterDepthMap(const PatchMatchOptions& o, const std::vector<const DepthNormalMap*>& sources, DepthNormalMap* m) {
  const PinholeCamera& cam = m->camera;
  ParallelFor(tbb::blocked_range<int>(0, cam.height, 8), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) {
      for (int x = 0; x < cam.width; ++x) {
        const double d = m->depth.at(x, y);
        if (!(d > 0)) continue;
        int consistent = 0;
        if (m->cost.at(x, y) <= o.max_cost && o.min_consistent_views > 0) {
          const Eigen::Vector3d X = cam.ToWorld(d * cam.Ray(x + 0.5, y + 0.5));
          for (size_t s = 0; s < sources.size() && consistent < o.min_consistent_views; ++s) {
            const PinholeCamera& sc = sources[s]->camera;
            const Eigen::Vector3d c = sc.ToCamera(X);
            if (!(c.z() > 0)) continue;
            const Eigen::Vector2d uv = sc.Project(c);
            if (!(uv.x() >= 0 && uv.y() >= 0 && uv.x() < sc.width && uv.y() < sc.height)) continue;
            const int sx = static_cast<int>(uv.x()), sy = static_cast<int>(uv.y());
            const double ds = sources[s]->depth.at(sx, sy);
            if (!(ds > 0)) continue;
            const Eigen::Vector3d back = cam.ToCamera(sc.ToWorld(ds * sc.Ray(sx + 0.5, sy + 0.5)));
            if (!(back.z() > 0)) continue;
            const double err = (cam.Project(back) - Eigen::Vector2d(x + 0.5, y + 0.5)).norm();
            if (err <= o.max_reprojection_error_px && std::abs(back.z() - d) <= o.max_depth_error * d) ++consistent;
          }
        }
        if (!(m->cost.at(x, y) <= o.max_cost && consistent >= o.min_consistent_views)) {
          m->depth.at(x, y) = 0;
          for (int c = 0; c < 3; ++c) m->normal.at(x, y, c) = 0;
        }
      }
    }
  });
}

SourceViewOptions PatchMatchOptions::Sources() const {
  SourceViewOptions s;
  s.num_sources = num_source_views;
  s.num_check_views = num_check_views;
  s.min_triangulation_angle_deg = min_triangulation_angle_deg;
  s.max_distance_ratio = max_distance_ratio;
  return s;
}

StereoPlan PlanStereo(const PatchMatchOptions& o, const StereoInput& input) {
  StereoPlan plan;
  std::vector<PinholeCamera> cameras;
  for (const StereoImage& image : input.images) cameras.push_back(image.camera);
  // A photo with no sparse point in front of it has no range: it gets no sources (an empty map,
  // reported), unless no photo has one, which is an error naming the fix.
  std::vector<uint8_t> no_range(cameras.size(), 0);
  std::exception_ptr first_failure;
  auto range = [&](size_t r, const std::vector<Eigen::Vector3d>& points) {
    try {
      return StereoDepthRange(o, cameras[r], points);
    } catch (const std::invalid_argument&) {
      if (!first_failure) first_failure = std::current_exception();
      no_range[r] = 1;
      return std::pair<double, double>(1, 2);  // never used: the photo has no sources
    }
  };
  auto finish = [&] {
    if (!cameras.empty() && std::count(no_range.begin(), no_range.end(), 1) == static_cast<long>(cameras.size()))
      std::rethrow_exception(first_failure);
    for (size_t r = 0; r < cameras.size(); ++r)
      if (no_range[r]) plan.links[r].sources.clear();
    return plan;
  };
  if (input.point_views.empty()) {
    // No tracks: every point for every range, then the geometric rule at the range's middle.
    for (size_t r = 0; r < cameras.size(); ++r) plan.ranges.push_back(range(r, input.sparse_points));
    for (size_t r = 0; r < cameras.size(); ++r)
      plan.links.push_back(SelectSourceViewsByAngle(o.Sources(), cameras, static_cast<int>(r),
                                                    std::sqrt(plan.ranges[r].first * plan.ranges[r].second)));
    return finish();
  }
  CANDI_CHECK(input.point_views.size() == input.sparse_points.size())
      << input.point_views.size() << " tracks, " << input.sparse_points.size() << " points";
  plan.links = SelectSourceViewsFromTracks(o.Sources(), cameras, input.sparse_points, input.point_views);
  // A photo's range: the points that it or its neighbours observe (those in its image count), so
  // the surface its neighbours see beyond its own tracks is in range too, at a cost bounded by
  // the neighbours, not the campaign.
  std::vector<std::vector<int>> observed(cameras.size());
  for (size_t k = 0; k < input.point_views.size(); ++k)
    for (int v : input.point_views[k])
      if (v >= 0 && static_cast<size_t>(v) < cameras.size() && (observed[v].empty() || observed[v].back() != static_cast<int>(k)))
        observed[v].push_back(static_cast<int>(k));
  const std::vector<std::vector<int>> neighbours = NeighbourViews(plan.links);
  std::vector<uint8_t> mark(input.sparse_points.size(), 0);
  for (size_t r = 0; r < cameras.size(); ++r) {
    std::vector<int> ids;
    auto add = [&](int v) {
      for (int k : observed[v])
        if (!mark[k]) mark[k] = 1, ids.push_back(k);
    };
    add(static_cast<int>(r));
    for (int v : neighbours[r]) add(v);
    std::sort(ids.begin(), ids.end());  // point order, as the rule without tracks reads them
    std::vector<Eigen::Vector3d> points;
    for (int k : ids) points.push_back(input.sparse_points[k]), mark[k] = 0;
    plan.ranges.push_back(range(r, points.empty() ? input.sparse_points : points));
  }
  return finish();
}

PatchMatchResult RunPatchMatch(const PatchMatchOptions& options, const StereoInput& input,
                               const ProgressCallback& progress) {
  options.Check();
  PatchMatchResult result;
  std::vector<StereoView> views;
  for (const StereoImage& image : input.images) views.push_back(PrepareStereoView(image, options.resolution_scale));
  uint64_t total = 0, done = 0;
  for (const StereoView& v : views)
    total += static_cast<uint64_t>(v.camera.width) * v.camera.height * (2 * options.iterations + 1);
  auto run = [&] {
    const StereoPlan plan = PlanStereo(options, input);
    const std::vector<std::pair<double, double>>& ranges = plan.ranges;
    const std::vector<ViewLinks>& links = plan.links;
    for (size_t r = 0; r < views.size(); ++r) {
      std::vector<const StereoView*> src;
      for (int s : links[r].sources) src.push_back(&views[s]);
      result.maps.push_back(MatchReference(options, views[r], static_cast<int>(r), src, links[r].sources, ranges[r],
                                           [&](uint64_t n) {
                                             done += n;
                                             if (progress) progress(done, total);
                                           }));
      result.maps.back().check_views = links[r].checks;
    }
    const std::vector<DepthNormalMap> raw = result.maps;  // read-only: the filter is order-independent
    const std::vector<std::vector<int>> neighbours = NeighbourViews(links);
    for (size_t r = 0; r < views.size(); ++r) {
      std::vector<const DepthNormalMap*> near;
      for (int s : neighbours[r]) near.push_back(&raw[s]);
      FilterDepthMap(options, near, &result.maps[r]);
    }
  };
  if (options.threads > 0) {
    tbb::task_arena arena(options.threads);
    arena.execute(run);
  } else {
    run();
  }
  for (const DepthNormalMap& m : result.maps) {
    result.total_pixels += static_cast<uint64_t>(m.camera.width) * m.camera.height;
    for (float d : m.depth.values()) result.valid_pixels += d > 0;
  }
  return result;
}

}  // namespace candi::photogrammetry

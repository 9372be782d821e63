#include "render/spbr.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/check.h"
#include "core/parallel.h"
#include "render/splat_kernel.h"

namespace candi::render {

void SpbrOptions::Check() const {
  CANDI_CHECK_OPTION_GE(ensembles, 0);
  CANDI_CHECK_OPTION_IN(threads, 0, 256);
}

namespace {

// c = R (origin + diag(step) q - eye) = (R diag(step)) q + R (origin - eye), in double, then float.
KernelTransform BlockTransform(const Camera::Projector& p, const SplatBlock& b, double depth_offset) {
  KernelTransform t;
  const Eigen::Vector3d origin(b.origin[0], b.origin[1], b.origin[2]);
  const Eigen::Vector3d offset = p.rotation * (origin - p.eye);
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) t.a[3 * r + c] = static_cast<float>(p.rotation(r, c) * b.step[c]);
    t.b[r] = static_cast<float>(offset[r] + (r == 2 ? depth_offset : 0.0));
  }
  return t;
}

// The rows a block can draw: its box's projection, widened by the splat size; `visible` false
// when the box lies wholly behind the near plane or beside the image.
struct BlockRows {
  int row0 = 0, row1 = 0;
  bool visible = false;
};

// From the block's bounding sphere (centre c, radius r in camera coordinates): one transform per
// block (blocks are many and small). For a sphere in front of the near plane, y/z over the sphere
// lies between the extremes of (c.y +- r) / (c.z +- r): a conservative row range.
BlockRows RowsOf(const Camera::Projector& p, const Camera& camera, const SplatBlock& b, double margin) {
  const Eigen::Vector3d lo(b.lo[0], b.lo[1], b.lo[2]), hi(b.hi[0], b.hi[1], b.hi[2]);
  const double r = 0.5 * (hi - lo).norm();
  const Eigen::Vector3d c = p.rotation * (0.5 * (lo + hi) - p.eye);
  BlockRows rows;
  if (p.perspective && c.z() + r <= p.near) return rows;           // wholly behind
  if (p.perspective && c.z() - r <= p.near) return {0, camera.height, true};  // straddles
  auto range = [&](double a, double center, double* lo_px, double* hi_px) {
    double mn = 1e300, mx = -1e300;
    for (double da : {-r, r}) {
      for (double dz : {-r, r}) {
        const double ratio = p.perspective ? (a + da) / (c.z() + dz) : (a + da);
        mn = std::min(mn, ratio), mx = std::max(mx, ratio);
      }
    }
    *lo_px = center + p.focal * mn - margin;
    *hi_px = center + p.focal * mx + margin;
  };
  double u0, u1, v0, v1;
  range(c.x(), p.cx, &u0, &u1);
  range(c.y(), p.cy, &v0, &v1);
  if (u1 < 0 || u0 >= camera.width || v1 < 0 || v0 >= camera.height) return rows;
  rows.row0 = static_cast<int>(std::clamp(std::floor(v0), 0.0, double(camera.height)));
  rows.row1 = static_cast<int>(std::clamp(std::floor(v1) + 1, 0.0, double(camera.height)));
  rows.visible = rows.row1 > rows.row0;
  return rows;
}

struct Frame {
  const SpbrOptions& options;
  const Camera& camera;
  const Camera::Projector& projector;
  const SplatCloud& cloud;
  std::vector<uint8_t> visible;  // per block
  int ensembles;
  // Orthographic views: added to every depth so all are positive (the kernel's keys order
  // positive floats by their bits); 0 for perspective views, whose drawn depths exceed near.
  double depth_offset = 0;
};


// One thread's frame: a z-buffer of keys, the sums of the ensembles it drew, and the grey
// histogram of ensemble 0 when it drew that one.
struct ThreadFrame {
  BandBuffer keys;
  Accumulator sums;
  GreyHistogram first_grey{};
  ThreadFrame(int w, int h) : sums(w, h) { keys.Reset(w, h); }
};

// Draws ensemble e into the thread's z-buffer and adds its pixels to the thread's sums.
void RenderEnsemble(const Frame& f, int e, ThreadFrame* t) {
  const int w = f.camera.width, h = f.camera.height;
  KernelProjection kp{static_cast<float>(f.projector.focal), static_cast<float>(f.projector.cx),
                      static_cast<float>(f.projector.cy),
                      f.projector.perspective ? static_cast<float>(f.projector.near)
                                              : -std::numeric_limits<float>::infinity(),
                      f.projector.perspective, w, h, 0, h};
  for (uint64_t k = f.cloud.ensemble_blocks[e]; k < f.cloud.ensemble_blocks[e + 1]; ++k) {
    if (!f.visible[k]) continue;
    const SplatBlock& b = f.cloud.blocks[k];
    const KernelTransform tr = BlockTransform(f.projector, b, f.depth_offset);
    const uint16_t* x = f.cloud.qx.data() + b.begin;
    const uint16_t* y = f.cloud.qy.data() + b.begin;
    const uint16_t* z = f.cloud.qz.data() + b.begin;
    const uint32_t* c = f.cloud.colors.data() + b.begin;
    if (f.cloud.point_size == 1.0) {
      SplatPoints(tr, kp, x, y, z, c, b.count, &t->keys);
    } else {
      SplatPointsSized(tr, kp, x, y, z, c, b.count, {f.cloud.point_size, f.cloud.seed, b.begin},
                       &t->keys);
    }
  }
  t->keys.DrainInto(&t->sums, e == 0 ? &t->first_grey : nullptr);
}

}  // namespace

SpbrResult RenderSpbr(const SpbrOptions& options, const Camera& camera, const SplatCloud& cloud,
                      const ProgressCallback& progress) {
  options.Check();
  const auto start = std::chrono::steady_clock::now();
  const Camera::Projector projector = camera.MakeProjector();
  const int L = cloud.repeat_level;
  CANDI_CHECK(static_cast<int>(cloud.ensemble_blocks.size()) == L + 1) << "SplatCloud not built";
  CANDI_CHECK(cloud.point_size >= 1 && cloud.point_size <= 64)
      << "SplatCloud::point_size = " << cloud.point_size;
  SpbrResult result;
  result.repeat_level = L;
  result.seed = cloud.seed;
  result.ensembles = options.ensembles > 0 ? std::min(options.ensembles, L) : L;
  result.copies = cloud.copies();
  Frame frame{options, camera, projector, cloud, {}, result.ensembles, OrthographicDepthOffset(projector, cloud.bounds)};
  frame.visible.resize(cloud.blocks.size());
  const double margin = 1.0 + cloud.point_size;
  tbb::enumerable_thread_specific<ThreadFrame> frames(camera.width, camera.height);
  std::atomic<int> done{0};
  auto body = [&] {
    ParallelFor(size_t{0}, cloud.blocks.size(), [&](size_t k) {
      frame.visible[k] = RowsOf(projector, camera, cloud.blocks[k], margin).visible;
    });
    // Ensembles are independent: each thread draws whole ensembles into its own frame.
    ParallelFor(0, result.ensembles, [&](int e) {
      RenderEnsemble(frame, e, &frames.local());
      const int d = ++done;
      if (progress) progress(d, result.ensembles);
    });
  };
  if (options.threads > 0) {
    tbb::task_arena arena(options.threads);
    arena.execute(body);
  } else {
    body();
  }
  // Integer sums: the merged result is the same whichever thread drew which ensemble.
  // The first thread's sums become the result's (no fresh frame to fault in and add to).
  bool first = true;
  for (ThreadFrame& t : frames) {
    if (first) result.sums = std::move(t.sums); else result.sums.Merge(t.sums);
    first = false;
    for (int i = 0; i < 256; ++i) result.first_ensemble_grey[i] += t.first_grey[i];
  }
  if (first) result.sums = Accumulator(camera.width, camera.height);  // no ensemble drawn
  result.milliseconds =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

double AutoBrightnessGain(const SpbrResult& result) {
  // T: the grey level at which the brightest 1 % of the first ensemble's pixels begin.
  uint64_t drawn = 0;
  for (uint64_t c : result.first_ensemble_grey) drawn += c;
  if (drawn == 0 || result.ensembles == 0) return 1.0;
  int t = 255;
  for (uint64_t above = 0; t > 0; --t) {
    above += result.first_ensemble_grey[t];
    if (above * 100 >= drawn) break;
  }
  // G: the same percentile of the averaged image's covered pixels (points' part only).
  std::vector<double> greys;
  const std::vector<uint32_t>& s = result.sums.sums;
  for (size_t i = 0; i + 3 < s.size(); i += 4) {
    if (s[i + 3] == 0) continue;
    greys.push_back((0.299 * s[i] + 0.587 * s[i + 1] + 0.114 * s[i + 2]) / result.ensembles);
  }
  if (greys.empty()) return 1.0;
  const size_t rank = greys.size() - 1 - (greys.size() - 1) / 100;
  std::nth_element(greys.begin(), greys.begin() + rank, greys.end());
  const double g = greys[rank];
  if (!(g > 0)) return 1.0;
  return std::max(1.0, std::ceil(t / g * 100.0 - 1e-9) / 100.0);
}

double BrightnessGain(const Brightness& brightness, const SpbrResult& result) {
  if (!brightness.automatic()) return brightness.gain();
  return result.ensembles > 1 ? AutoBrightnessGain(result) : 1.0;
}

ImageF AverageImage(const SpbrResult& result, Rgb8 background, double gain) {
  const Accumulator& a = result.sums;
  ImageF image(a.width, a.height, 3);
  const double k = std::max(1, result.ensembles);
  const double bg[3] = {double(background.r), double(background.g), double(background.b)};
  for (size_t p = 0; p < static_cast<size_t>(a.width) * a.height; ++p) {
    const uint32_t* s = &a.sums[4 * p];
    const double empty = k - s[3];
    for (int c = 0; c < 3; ++c) {
      const double v = (gain * s[c] + empty * bg[c]) / k;
      image.data()[3 * p + c] = static_cast<float>(std::clamp(v, 0.0, 255.0));
    }
  }
  return image;
}

Image8 ToImage8(const ImageF& average) {
  Image8 out(average.width(), average.height(), average.channels());
  for (size_t i = 0; i < average.values().size(); ++i) {
    out.values()[i] = static_cast<uint8_t>(std::lround(std::clamp(average.values()[i], 0.0f, 255.0f)));
  }
  return out;
}

Image16 ToImage16(const ImageF& average) {
  Image16 out(average.width(), average.height(), average.channels());
  for (size_t i = 0; i < average.values().size(); ++i) {
    const double v = std::clamp(static_cast<double>(average.values()[i]), 0.0, 255.0) * 257.0;
    out.values()[i] = static_cast<uint16_t>(std::lround(v));
  }
  return out;
}

}  // namespace candi::render

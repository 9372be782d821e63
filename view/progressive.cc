#include "view/progressive.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/check.h"

namespace candi::view {

RangeRenderer LocalRangeRenderer(const render::Archive& archive) {
  return [&archive](const render::ArchiveRenderOptions& options, const render::Camera& camera,
                    const std::function<bool()>& cancel) {
    ProgressCallback progress;
    if (cancel) {
      progress = [&cancel](uint64_t, uint64_t) {
        if (cancel()) throw Cancelled{};
      };
    }
    return render::RenderArchive(options, camera, archive, progress);
  };
}

ProgressiveImage::ProgressiveImage(const render::Archive& archive, RangeRenderer renderer, int threads)
    : archive_(archive), renderer_(std::move(renderer)), threads_(threads) {}

void ProgressiveImage::Start(const ViewState& state) {
  state.camera.Check();
  const size_t layers = archive_.manifest().layers.size();
  if (!state.settings.layer_fraction.empty() && state.settings.layer_fraction.size() != layers) {
    throw std::invalid_argument("/settings/layers: " + std::to_string(state.settings.layer_fraction.size()) +
                                " values for an archive of " + std::to_string(layers) + " layers");
  }
  state_ = state;
  started_ = true;
  drawn_ = 0;
  sums_ = render::SpbrResult();
  sums_.sums = render::Accumulator(state.camera.width, state.camera.height);
  sums_.repeat_level = repeat_level();
  sums_.seed = state.settings.seed;
}

double ProgressiveImage::Step(int count, const std::function<bool()>& cancel) {
  CANDI_CHECK(started_) << "Start first";
  const int L = repeat_level();
  if (drawn_ == L) return 0;
  count = std::clamp(count, 1, L - drawn_);
  const auto start = std::chrono::steady_clock::now();
  render::ArchiveRenderOptions o;
  o.repeat_level = L;
  o.seed = state_.settings.seed;
  o.point_size = state_.settings.point_size;
  o.threads = threads_;
  o.ensemble_begin = drawn_;
  o.ensemble_end = drawn_ + count;
  o.layer_fraction = state_.settings.layer_fraction;
  // Previews read only their slices of each chunk; the step that completes the image checks the
  // hashes of the chunks it draws (once per chunk: Archive remembers), as candi render does.
  o.verify = drawn_ + count == L;
  render::Camera local = state_.camera;
  local.eye -= archive_.manifest().frame.origin;
  local.target -= archive_.manifest().frame.origin;
  const render::SpbrResult part = renderer_(o, local, cancel);
  sums_.sums.Merge(part.sums);
  for (int i = 0; i < 256; ++i) sums_.first_ensemble_grey[i] += part.first_ensemble_grey[i];
  sums_.copies += part.copies;
  drawn_ += count;
  sums_.ensembles = drawn_;
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ms_per_ensemble_ = ms / count;
  return ms;
}

Image8 ProgressiveImage::Image(double* gain) const {
  CANDI_CHECK(started_) << "Start first";
  const double b = state_.settings.brightness;
  // As candi render (apps/cmd_render.cc WriteOutputs): automatic gain needs more than one ensemble.
  const double g = b < 0 ? (sums_.ensembles > 1 ? render::AutoBrightnessGain(sums_) : 1.0) : b;
  if (gain) *gain = g;
  return render::ToImage8(render::AverageImage(sums_, state_.settings.background, g));
}

int StepPolicy::Ensembles(double ms_per_ensemble, int step) const {
  const double per = ms_per_ensemble > 0 ? ms_per_ensemble : first_frame_ms;
  const double budget = std::min(step_ms, first_frame_ms * std::pow(2.0, std::min(step, 30)));
  return std::max(1, static_cast<int>(std::min(budget / per, 1e6)));
}

PickResult PickPoint(const render::Archive& archive, const render::Camera& camera, double u, double v,
                     double radius_px) {
  camera.Check();
  const render::Camera::Projector p = camera.MakeProjector();
  const render::ArchiveManifest& m = archive.manifest();
  PickResult best;
  best.depth = std::numeric_limits<double>::infinity();
  const double r2 = radius_px * radius_px;
  PointCloud points;
  for (size_t k = 0; k < m.chunks.size(); ++k) {
    const Box3d& box = m.chunks[k].quantizer.box;
    double lo_u = std::numeric_limits<double>::infinity(), hi_u = -lo_u, lo_v = lo_u, hi_v = -lo_u;
    bool behind = false;
    for (int c = 0; c < 8 && !behind; ++c) {
      const Eigen::Vector3d x(c & 1 ? box.max.x() : box.min.x(), c & 2 ? box.max.y() : box.min.y(),
                              c & 4 ? box.max.z() : box.min.z());
      double cu = 0, cv = 0, depth = 0;
      if (!p.Project(x, &cu, &cv, &depth)) behind = true;
      lo_u = std::min(lo_u, cu), hi_u = std::max(hi_u, cu), lo_v = std::min(lo_v, cv), hi_v = std::max(hi_v, cv);
    }
    // A box partly behind the camera may wrap: read it. Otherwise its projection (the hull of
    // its corners' projections) must hold the pixel's neighbourhood.
    if (!behind && (u + radius_px < lo_u || u - radius_px > hi_u || v + radius_px < lo_v || v - radius_px > hi_v)) {
      continue;
    }
    archive.ReadChunk(k, &points, /*verify=*/true);
    for (size_t i = 0; i < points.size(); ++i) {
      double pu, pv, depth;
      if (!p.Project(points.positions[i], &pu, &pv, &depth)) continue;
      const double du = pu - u, dv = pv - v;
      if (du * du + dv * dv > r2 || depth >= best.depth) continue;
      best.hit = true;
      best.depth = depth;
      best.local = points.positions[i];
    }
  }
  if (!best.hit) best.depth = 0;
  return best;
}

}  // namespace candi::view

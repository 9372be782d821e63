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
    render::ArchiveRenderOptions o = options;
    o.cancel = cancel;  // polled by the drawing threads, also within a chunk
    try {
      return render::RenderArchive(o, camera, archive);
    } catch (const render::RenderCancelled&) {
      throw Cancelled{};
    }
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
  sample_ = 1;
  sums_ = render::SpbrResult();
  sums_.sums = render::Accumulator(state.camera.width, state.camera.height);
  sums_.repeat_level = repeat_level();
  sums_.seed = state.settings.spbr.seed;
}

double ProgressiveImage::Step(int count, const std::function<bool()>& cancel, double sample) {
  CANDI_CHECK(started_) << "Start first";
  CANDI_CHECK(sample > 0 && sample <= 1) << "sample " << sample;
  const int L = repeat_level();
  if (drawn_ == L) return 0;
  const bool preview = sample < 1 && drawn_ == 0;
  count = preview ? 1 : std::clamp(count, 1, L - drawn_);
  const auto start = std::chrono::steady_clock::now();
  render::ArchiveRenderOptions o;
  o.spbr = state_.settings.spbr;
  o.threads = threads_;
  o.ensemble_begin = drawn_;
  o.ensemble_end = drawn_ + count;
  o.layer_fraction = state_.settings.layer_fraction;
  o.clip = state_.settings.clip.ToLocal(archive_.manifest().frame.origin);
  o.sample = preview ? sample : 1.0;
  // Previews read only their slices of each chunk; the step that completes the image checks the
  // hashes of the chunks it draws (once per chunk: Archive remembers), as candi render does.
  o.verify = drawn_ + count == L && !preview;
  render::Camera local = state_.camera;
  local.eye -= archive_.manifest().frame.origin;
  local.target -= archive_.manifest().frame.origin;
  const render::SpbrResult part = renderer_(o, local, cancel);
  if (preview || sample_ < 1) {  // a preview replaces, and is replaced by, what follows it
    sums_.sums = render::Accumulator(state_.camera.width, state_.camera.height);
    sums_.first_ensemble_grey = {};
    sums_.copies = 0;
    sample_ = preview ? sample : 1.0;
  }
  sums_.sums.Merge(part.sums);
  for (int i = 0; i < 256; ++i) sums_.first_ensemble_grey[i] += part.first_ensemble_grey[i];
  sums_.copies += part.copies;
  if (!preview) drawn_ += count;
  sums_.ensembles = preview ? 1 : drawn_;
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ms_per_ensemble_ = preview ? ms / sample : ms / count;
  return ms;
}

double ProgressiveImage::EnsembleFootprint() const {
  CANDI_CHECK(started_) << "Start first";
  const render::ArchiveManifest& m = archive_.manifest();
  const std::vector<double>& f = state_.settings.layer_fraction;
  double points = 0;
  for (size_t k = 0; k < m.layers.size(); ++k) {
    points += static_cast<double>(m.layers[k].points) * (f.empty() ? 1.0 : f[k]);
  }
  const double size = state_.settings.spbr.point_size;
  const double area = std::min(size * size, static_cast<double>(state_.camera.width) * state_.camera.height);
  return points / repeat_level() * area;
}

Image8 ProgressiveImage::Image(double* gain) const {
  CANDI_CHECK(started_) << "Start first";
  const double g = render::BrightnessGain(state_.settings.brightness, sums_);  // as candi render's
  if (gain) *gain = g;
  return render::ToImage8(render::AverageImage(sums_, state_.settings.background, g));
}

int StepPolicy::Ensembles(double ms_per_ensemble, int step) const {
  const double per = ms_per_ensemble > 0 ? ms_per_ensemble : first_frame_ms;
  const double budget = std::min(step_ms, first_frame_ms * std::pow(2.0, std::min(step, 30)));
  return std::max(1, static_cast<int>(std::min(budget / per, 1e6)));
}

namespace {

// Per point of a chunk: whether the layer's share draws it (some ensemble's run holds it).
std::vector<char> DrawnPoints(const render::ArchiveChunk& c, const PickOptions& o) {
  const double f = o.layer_fraction.empty() ? 1.0 : o.layer_fraction[c.layer];
  std::vector<char> drawn(c.count, f >= 1 ? 1 : 0);
  if (f >= 1) return drawn;
  std::vector<render::PointRun> runs;
  const int L = o.spbr.EffectiveRepeatLevel();
  for (int e = 0; e < L; ++e) {
    runs.clear();
    render::EnsembleSlices(c.count, c.first, L, o.spbr.seed, e, f, &runs);
    for (const render::PointRun& r : runs) std::fill(drawn.begin() + r.begin, drawn.begin() + r.end, 1);
  }
  return drawn;
}

}  // namespace

void PickOptions::Check() const {
  CANDI_CHECK_OPTION(radius_px >= 0 && std::isfinite(radius_px), radius_px, "finite and >= 0");
  spbr.Check();
  CANDI_CHECK_OPTION_EACH_IN(layer_fraction, 0, 16);
  clip.Check("PickOptions::clip");
}

PickResult PickPoint(const render::Archive& archive, const render::Camera& camera, double u, double v,
                     const PickOptions& o) {
  o.Check();
  camera.Check();
  const render::Camera::Projector p = camera.MakeProjector();
  const render::ArchiveManifest& m = archive.manifest();
  if (!o.layer_fraction.empty() && o.layer_fraction.size() != m.layers.size()) {
    throw std::invalid_argument("pick: " + std::to_string(o.layer_fraction.size()) + " layer shares for " +
                                std::to_string(m.layers.size()) + " layers");
  }
  std::vector<PickHit> best(m.layers.size());
  for (PickHit& h : best) h.depth = std::numeric_limits<double>::infinity();
  const double r2 = o.radius_px * o.radius_px;
  PointCloud points;
  for (size_t k = 0; k < m.chunks.size(); ++k) {
    const render::ArchiveChunk& chunk = m.chunks[k];
    if (!o.layer_fraction.empty() && o.layer_fraction[chunk.layer] == 0) continue;  // hidden
    const Box3d& box = chunk.quantizer.box;
    if (o.clip.Classify(box) == ClipRelation::kOutside) continue;
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
    if (!behind && (u + o.radius_px < lo_u || u - o.radius_px > hi_u || v + o.radius_px < lo_v || v - o.radius_px > hi_v)) {
      continue;
    }
    archive.ReadChunk(k, &points, /*verify=*/true);
    const std::vector<char> drawn = DrawnPoints(chunk, o);
    PickHit& b = best[chunk.layer];
    for (size_t i = 0; i < points.size(); ++i) {
      double pu, pv, depth;
      if (!drawn[i] || !p.Project(points.positions[i], &pu, &pv, &depth)) continue;
      const double du = pu - u, dv = pv - v;
      if (du * du + dv * dv > r2 || depth >= b.depth) continue;
      if (!o.clip.Contains(points.positions[i])) continue;
      b.layer = chunk.layer;
      b.depth = depth;
      b.local = points.positions[i];
      if (points.schema.colors) b.colour = points.colors[i];
    }
  }
  PickResult result;
  for (const PickHit& h : best) {
    if (std::isfinite(h.depth)) result.hits.push_back(h);
  }
  std::stable_sort(result.hits.begin(), result.hits.end(),
                   [](const PickHit& a, const PickHit& b) { return a.depth < b.depth; });
  if (!result.hits.empty()) {
    result.hit = true;
    result.local = result.hits[0].local;
    result.depth = result.hits[0].depth;
  }
  return result;
}

}  // namespace candi::view

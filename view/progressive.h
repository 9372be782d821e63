// Progressive SPBR of a render archive: ensembles accumulate while the camera rests.
//
// Each ensemble of SPBR is an independent image, and their integer sums add exactly, so an image
// drawn in batches of ensembles [0, k1), [k1, k2), ... equals, bit for bit, the image of all L
// drawn at once: once converged (k = L) the pixels are those `candi render` writes for the same
// archive, view, seed and L (the same gain, the same rounding). Before that the image is the
// average of the first k ensembles: an unbiased, noisier estimate of the final one.
#pragma once

#include <cstdint>
#include <functional>

#include "core/image.h"
#include "render/archive.h"
#include "render/archive_render.h"
#include "render/spbr.h"
#include "view/protocol.h"

namespace candi::view {

// Draws the ensembles options.ensemble_begin..end of `local_camera` (the archive's frame): by
// default RenderArchive; under MPI, every rank's share reduced on rank 0. `cancel` is polled
// between chunk groups and aborts the draw (throws Cancelled) when it returns true.
struct Cancelled {};
using RangeRenderer = std::function<render::SpbrResult(const render::ArchiveRenderOptions& options,
                                                       const render::Camera& local_camera,
                                                       const std::function<bool()>& cancel)>;
RangeRenderer LocalRangeRenderer(const render::Archive& archive);

class ProgressiveImage {
 public:
  ProgressiveImage(const render::Archive& archive, RangeRenderer renderer, int threads);

  // Begins the image of `state` (camera in world coordinates); the drawn ensembles are dropped.
  void Start(const ViewState& state);
  const ViewState& state() const { return state_; }
  int ensembles() const { return drawn_; }  // 0 after a sampled preview
  int repeat_level() const { return state_.settings.spbr.EffectiveRepeatLevel(); }
  bool converged() const { return started_ && drawn_ == repeat_level(); }

  // Draws the next `count` ensembles (at least one, at most those left); returns milliseconds.
  // Throws Cancelled (nothing added) when `cancel` says so.
  //
  // With `sample` < 1 (before any ensemble is drawn) it draws instead a preview: a random `sample`
  // of the first ensemble's points (ArchiveRenderOptions::sample), shown by Image() but not
  // counted; the next step starts the accumulation afresh. The viewer's bound on a first frame
  // whose ensemble would take long (large point footprints: EnsembleFootprint).
  double Step(int count, const std::function<bool()>& cancel = nullptr, double sample = 1.0);
  bool sampled() const { return sample_ < 1; }
  double sample() const { return sample_; }
  // Milliseconds an ensemble took in the last step (0 before any; after a preview, its time
  // scaled to the whole ensemble).
  double ms_per_ensemble() const { return ms_per_ensemble_; }
  // The pixels one ensemble may write, an upper bound: the points it draws (every shown layer's
  // share, frustum and clipping ignored) times a point's area (point_size², at most the image).
  double EnsembleFootprint() const;

  // The image of the ensembles drawn so far and its brightness gain (candi render's rule: the
  // scene's gain, or automatic from the first ensemble when more than one is drawn).
  Image8 Image(double* gain) const;

 private:
  const render::Archive& archive_;
  RangeRenderer renderer_;
  int threads_;
  ViewState state_;
  bool started_ = false;
  int drawn_ = 0;
  render::SpbrResult sums_;
  double ms_per_ensemble_ = 0;
  double sample_ = 1;  // < 1: sums_ hold a preview (not counted in drawn_)
};

// How many ensembles a step draws: after a camera change as many as fit first_frame_ms (the
// preview while the camera moves), then each step twice the budget of the one before, up to
// step_ms, so the image converges in few steps and a new camera waits at most one step.
struct StepPolicy {
  double first_frame_ms = 40, step_ms = 400;
  // `ms_per_ensemble`: the last step's (0 before any); `step`: steps since the image started.
  int Ensembles(double ms_per_ensemble, int step) const;
};

// The archived points drawn within `radius_px` of pixel (u, v) of `local_camera` (1-pixel
// points; reads only the chunks whose projected boxes hold the pixel): the nearest of each layer,
// nearest first. Only what is shown counts: a layer at share 0 is skipped, a layer at share f < 1
// offers only the points its ensembles draw (render/archive.h EnsembleSlices at repeat level L
// and seed), and points outside `clip` (the archive's frame) are skipped.
struct PickOptions {
  double radius_px = 3;                // pixels, finite and >= 0
  SpbrSettings spbr;                   // the render's L (1 when opaque) and seed
  std::vector<double> layer_fraction;  // per archive layer, each in [0, 16]; empty: all 1
  ClipRegion clip;                     // archive frame; finite planes with non-zero normals
  void Check() const;                  // throws std::invalid_argument naming the field
};
struct PickHit {
  int layer = 0;
  Eigen::Vector3d local = Eigen::Vector3d::Zero();  // archive frame
  double depth = 0;
  Rgb8 colour;                                      // the point's stored colour
};
struct PickResult {
  bool hit = false;
  Eigen::Vector3d local = Eigen::Vector3d::Zero();  // archive frame: the nearest hit
  double depth = 0;
  std::vector<PickHit> hits;                        // per layer, nearest first
};
PickResult PickPoint(const render::Archive& archive, const render::Camera& local_camera, double u, double v,
                     const PickOptions& options);

}  // namespace candi::view

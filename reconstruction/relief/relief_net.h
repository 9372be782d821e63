// The relief depth network: BTS (Lee et al., "From Big to Small: Multi-Scale Local Planar
// Guidance for Monocular Depth Estimation", 2019) scaled for a CPU, in libtorch.
//
// Topology as BTS: a DenseNet-BC encoder (conv 7x7/2, max-pool, four dense blocks with
// transitions; skips at 1/2, 1/4, 1/8, 1/16), a decoder with dense ASPP (dilations 3, 6, 12, 18,
// 24) at 1/8, local planar guidance (LPG) at 1/8, 1/4 and 1/2, and a sigmoid head scaled to
// max_depth levels. Input: one grey channel, side a multiple of 32, normalised as (v - 0.5) / 0.25.
// Output: depth levels (relief_image.h). LPG planes have their normal's polar angle limited to
// pi/6 (not the reference code's pi/3), so the denominator n1 u + n2 v + n3 >= cos(pi/6) -
// sin(pi/6) / sqrt(2) > 0.5 at every patch position: no division by zero.
//
// libtorch stays out of this header (pimpl). The model file (torch serialize archive) holds the
// options, the training resolution and the weights. Not thread-safe: one model per thread.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/image.h"
#include "core/progress.h"
#include "reconstruction/relief/relief_tiles.h"

namespace candi::relief {

struct NetOptions {
  int growth = 12;                       // DenseNet growth rate k, [2, 64]
  std::vector<int> blocks = {4, 6, 8, 6};  // dense layers in each of the 4 blocks, each [1, 64]
  int decoder_width = 128;               // BTS "num_features" (512 in the paper), multiple of 16, [32, 1024]
  double max_depth = 255;                // scale of the sigmoid head, levels, > 0
  // The head's levels are relative: right up to an unknown scale and offset per image (trained
  // with the scale-and-shift-invariant loss, relief_train.h). Such a model predicts a whole image
  // at once (tiles would each get their own scale), is scored after the least-squares scale and
  // offset like the baselines, and its output is stretched for use (PredictOptions::stretch).
  bool relative = false;
  void Check() const;                    // throws std::invalid_argument naming the field
};

// Sets libtorch's intra-op threads for the process (1 by default in candi: on a busy 2-core
// machine two threads were up to 15x slower). threads >= 1.
void SetTorchThreads(int threads);

struct PredictOptions {
  TileOptions tiles;          // tile 128, overlap 32 (tile must be a multiple of 32)
  double photo_pixels_per_m = 0;  // the photo's resolution; 0 = the model's (no resampling)
  // A relative model's levels stretched linearly so that their 2nd and 98th percentiles become
  // levels 1 and 255 (the convention of photo pairs, relief_photo_pairs.h), clamped to [0, 255];
  // false: as the network gives them (for scoring after a fit). No effect on absolute models.
  bool stretch = true;
  void Check() const;
};

class DepthModel {
 public:
  struct Impl;  // defined in relief_net_internal.h (libtorch)

  // A new model with weights initialised from `seed` (deterministic).
  static DepthModel Create(const NetOptions& options, uint64_t seed);
  // Throws InputError naming the path when the file is missing or not a candi relief model.
  static DepthModel Load(const std::string& path);
  // Writes atomically.
  void Save(const std::string& path) const;

  const NetOptions& options() const;
  int64_t ParameterCount() const;
  double pixels_per_m() const;           // resolution of the training data, pixels per metre
  void set_pixels_per_m(double value);
  // Makes the model relative (NetOptions::relative), e.g. before fine-tuning an absolute one
  // with the scale-and-shift-invariant loss; the weights stay.
  void set_relative(bool relative);

  // Depth levels of one tile (side a multiple of 32, one channel, grey [0, 1]); eval mode.
  ImageF PredictTile(const ImageF& tile) const;
  // A whole photo of any size: resampled to the model's resolution, predicted in overlapping
  // tiles blended without seams (a relative model: in one piece, edge-padded to a multiple of
  // 32), resampled back to the photo's size. NaN pixels read as 0.5.
  ImageF Predict(const PredictOptions& options, const ImageF& photo,
                 const ProgressCallback& progress = nullptr) const;
  // One image of any size in one piece (edge-padded to a multiple of 32, cropped back), at the
  // model's resolution, not stretched.
  ImageF PredictWhole(const ImageF& image) const;

  Impl& impl() const { return *impl_; }

 private:
  explicit DepthModel(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}
  std::shared_ptr<Impl> impl_;
};

// Levels stretched linearly so that their 2nd and 98th percentiles become levels 1 and 255,
// clamped to [0, 255]; a flat image becomes the middle level. Non-finite values stay.
ImageF StretchRelative(const ImageF& levels);

}  // namespace candi::relief

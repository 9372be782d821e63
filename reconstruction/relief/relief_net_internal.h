// libtorch internals of the relief network, shared by relief_net.cc, relief_train.cc and their
// tests. Include only from .cc files: <torch/torch.h> costs ~30 s per translation unit.
#pragma once

#include <torch/torch.h>

#include "reconstruction/relief/panel_size.h"
#include "reconstruction/relief/relief_net.h"

namespace candi::relief {

// Local planar guidance. plane: B x 4 x H x W (unit normal n1 n2 n3, distance n4). Returns
// B x (H r) x (W r): each coarse cell's r x r patch gets n4 / (n1 u + n2 v + n3) with
// (u, v) = ((col - (r - 1) / 2) / r, (row - (r - 1) / 2) / r) the offset inside the patch.
torch::Tensor LocalPlanarGuidance(const torch::Tensor& plane, int ratio);

// Plane parameters from three raw channels (B x 3 x H x W): theta = sigmoid * pi / 6 (polar
// angle of the normal), phi = sigmoid * 2 pi, distance = sigmoid * max_depth. B x 4 x H x W.
torch::Tensor PlaneFromRaw(const torch::Tensor& raw, double max_depth);

// Scale-invariant log loss (Eigen et al. 2014, BTS's lambda 0.85, x10) over mask (bool) pixels:
// 10 sqrt(mean d^2 - 0.85 mean(d)^2), d = ln pred - ln gt. Zero (with gradient) when mask is empty.
torch::Tensor SilogLoss(const torch::Tensor& pred, const torch::Tensor& gt, const torch::Tensor& mask);

// pred moved by each image's least-squares scale and offset onto gt over its mask (bool) pixels,
// as relief_baselines.h's FitLevels does for scoring (differentiable; centred sums, so float
// stays exact enough for 10^5 pixels of 255 levels). An image without mask pixels, or a flat
// prediction, gets scale 0 and offset the mean of gt (0 without pixels).
torch::Tensor AlignScaleShift(const torch::Tensor& pred, const torch::Tensor& gt, const torch::Tensor& mask);

// The scale-and-shift-invariant loss of a relative model (after MiDaS, Ranftl et al. 2020, here
// with the least-squares alignment the scores use): pred aligned per image (AlignScaleShift),
// clamped to [kMinValidLevel, kMaxLevel], then the RMSE of log levels over the mask, averaged
// over the images that have mask pixels, x10 like the SI-log loss. The same for a pred + b, any
// a != 0 and b: the fit takes the sign too.
torch::Tensor ScaleShiftInvariantLoss(const torch::Tensor& pred, const torch::Tensor& gt, const torch::Tensor& mask);

// Grey [0, 1] images (same size) to a B x 1 x H x W normalised input tensor.
torch::Tensor PhotoBatch(const std::vector<const ImageF*>& photos);

struct BtsNetImpl : torch::nn::Module {
  explicit BtsNetImpl(const NetOptions& options);
  torch::Tensor forward(const torch::Tensor& x);  // B x 1 x H x W -> B x 1 x H x W levels

  NetOptions options;
  torch::nn::Sequential encoder_stem{nullptr};           // conv0, norm0, relu0 (1/2)
  torch::nn::MaxPool2d pool0{nullptr};                   // 1/4
  std::vector<torch::nn::Sequential> blocks, transitions;  // 4 blocks, 3 transitions
  torch::nn::Sequential norm5{nullptr};
  torch::nn::ModuleDict decoder{nullptr};  // BTS decoder modules by their BTS names
};
TORCH_MODULE(BtsNet);

struct DepthModel::Impl {
  explicit Impl(const NetOptions& o) : net(o) {}
  BtsNet net;
  double pixels_per_m = 800 / kPanelWidthM;
};

// The model file's archive (options, resolution, weights), shared with training checkpoints.
void WriteModelArchive(const DepthModel::Impl& impl, torch::serialize::OutputArchive* archive);
std::shared_ptr<DepthModel::Impl> ReadModelArchive(torch::serialize::InputArchive& archive);
// The tensor stored under `key` (always a new tensor: see the .cc).
torch::Tensor ReadTensor(torch::serialize::InputArchive& archive, const char* key);
// Serialises an archive to `path` atomically.
void SaveArchive(torch::serialize::OutputArchive& archive, const std::string& path);

}  // namespace candi::relief

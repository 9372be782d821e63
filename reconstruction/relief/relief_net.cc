#include "reconstruction/relief/relief_net.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "core/atomic_file.h"
#include "core/check.h"
#include "reconstruction/relief/relief_image.h"
#include "reconstruction/relief/relief_net_internal.h"

namespace candi::relief {

namespace {

namespace nn = torch::nn;
using torch::indexing::None;
using torch::indexing::Slice;

constexpr double kPi = 3.14159265358979323846;
constexpr int64_t kModelVersion = 1;

nn::Conv2d Conv(int in, int out, int k, int stride = 1, int dilation = 1) {
  return nn::Conv2d(nn::Conv2dOptions(in, out, k).stride(stride).padding(dilation * (k / 2))
                        .dilation(dilation).bias(false));
}

// DenseNet-BC layer: BN-ReLU-Conv1x1(4k)-BN-ReLU-Conv3x3(k), concatenated to its input.
struct DenseLayerImpl : nn::Module {
  DenseLayerImpl(int in, int growth)
      : body(nn::BatchNorm2d(in), nn::ReLU(), Conv(in, 4 * growth, 1), nn::BatchNorm2d(4 * growth),
             nn::ReLU(), Conv(4 * growth, growth, 3)) {
    register_module("body", body);
  }
  torch::Tensor forward(const torch::Tensor& x) { return torch::cat({x, body->forward(x)}, 1); }
  nn::Sequential body;
};
TORCH_MODULE(DenseLayer);

// BTS upconv: nearest x2, conv 3x3, ELU.
nn::Sequential Upconv(int in, int out) {
  return nn::Sequential(
      nn::Upsample(nn::UpsampleOptions().scale_factor(std::vector<double>{2, 2}).mode(torch::kNearest)),
      Conv(in, out, 3), nn::ELU());
}

nn::Sequential ConvElu(int in, int out) { return nn::Sequential(Conv(in, out, 3), nn::ELU()); }

// BTS atrous_conv: [BN], ReLU, conv 1x1 (2 out), BN, ReLU, dilated conv 3x3 (out).
nn::Sequential Atrous(int in, int out, int dilation, bool bn_first) {
  nn::Sequential s;
  if (bn_first) s->push_back(nn::BatchNorm2d(in));
  s->push_back(nn::ReLU());
  s->push_back(Conv(in, 2 * out, 1));
  s->push_back(nn::BatchNorm2d(2 * out));
  s->push_back(nn::ReLU());
  s->push_back(Conv(2 * out, out, 3, 1, dilation));
  return s;
}

// BTS reduction_1x1: 1x1 convs (ELU) halving from `start` while >= 8, then 3 raw plane
// channels, or (final) one sigmoid channel.
nn::Sequential Reduction(int in, int start, bool final) {
  nn::Sequential s;
  for (int out = start; out >= 8; out /= 2) {
    s->push_back(nn::Conv2d(nn::Conv2dOptions(in, out, 1).bias(false)));
    s->push_back(nn::ELU());
    in = out;
  }
  s->push_back(nn::Conv2d(nn::Conv2dOptions(in, final ? 1 : 3, 1).bias(false)));
  if (final) s->push_back(nn::Sigmoid());
  return s;
}

// Every other row and column of a B x 1 x H x W tensor by `step` (nearest downsampling).
torch::Tensor Every(const torch::Tensor& x, int step) {
  return x.index({Slice(), Slice(), Slice(None, None, step), Slice(None, None, step)});
}

}  // namespace

void NetOptions::Check() const {
  CANDI_CHECK_OPTION_IN(growth, 2, 64);
  CANDI_CHECK_OPTION_MSG(blocks.size() == 4, blocks, "must have 4 entries");
  CANDI_CHECK_OPTION_EACH_IN(blocks, 1, 64);
  CANDI_CHECK_OPTION(decoder_width >= 32 && decoder_width <= 1024 && decoder_width % 16 == 0,
                     decoder_width, "a multiple of 16 in [32, 1024]");
  CANDI_CHECK_OPTION_GT(max_depth, 0);
}

void PredictOptions::Check() const {
  tiles.Check();
  CANDI_CHECK_OPTION(tiles.tile % 32 == 0, tiles.tile, "a multiple of 32");
  CANDI_CHECK_OPTION_GE(photo_pixels_per_m, 0);
}

void SetTorchThreads(int threads) {
  CANDI_CHECK(threads >= 1) << threads;
  torch::set_num_threads(threads);
}

torch::Tensor LocalPlanarGuidance(const torch::Tensor& plane, int ratio) {
  CANDI_CHECK(plane.dim() == 4 && plane.size(1) == 4) << plane.sizes();
  const torch::Tensor p = plane.repeat_interleave(ratio, 2).repeat_interleave(ratio, 3);
  const torch::Tensor offset =
      (torch::arange(ratio, plane.options()) - (ratio - 1) * 0.5) / static_cast<double>(ratio);
  const torch::Tensor u = offset.repeat({plane.size(3)}).view({1, 1, -1});
  const torch::Tensor v = offset.repeat({plane.size(2)}).view({1, -1, 1});
  return p.select(1, 3) / (p.select(1, 0) * u + p.select(1, 1) * v + p.select(1, 2));
}

torch::Tensor PlaneFromRaw(const torch::Tensor& raw, double max_depth) {
  const torch::Tensor theta = torch::sigmoid(raw.select(1, 0)) * (kPi / 6);
  const torch::Tensor phi = torch::sigmoid(raw.select(1, 1)) * (2 * kPi);
  const torch::Tensor dist = torch::sigmoid(raw.select(1, 2)) * max_depth;
  return torch::stack({torch::sin(theta) * torch::cos(phi), torch::sin(theta) * torch::sin(phi),
                       torch::cos(theta), dist}, 1);
}

torch::Tensor SilogLoss(const torch::Tensor& pred, const torch::Tensor& gt, const torch::Tensor& mask) {
  if (mask.sum().item<int64_t>() == 0) return pred.sum() * 0.0;
  const torch::Tensor d = torch::log(pred.masked_select(mask)) - torch::log(gt.masked_select(mask));
  // clamp: float rounding can make the variance term slightly negative when d is constant.
  return torch::sqrt(torch::clamp_min((d * d).mean() - 0.85 * d.mean().pow(2), 1e-12)) * 10.0;
}

torch::Tensor AlignScaleShift(const torch::Tensor& pred, const torch::Tensor& gt, const torch::Tensor& mask) {
  const torch::Tensor m = mask.to(torch::kFloat);
  const std::vector<int64_t> dims = {1, 2, 3};
  const torch::Tensor n = m.sum(dims, true);
  const torch::Tensor safe_n = torch::clamp_min(n, 1.0);
  const torch::Tensor mean_p = (pred * m).sum(dims, true) / safe_n;
  const torch::Tensor mean_g = (gt * m).sum(dims, true) / safe_n;
  const torch::Tensor dp = (pred - mean_p) * m;
  const torch::Tensor var = (dp * dp).sum(dims, true);
  const torch::Tensor cov = (dp * (gt - mean_g)).sum(dims, true);
  // A flat prediction has no scale to fit: 0, without dividing by (almost) 0.
  const torch::Tensor ok = var > 1e-10 * safe_n;
  const torch::Tensor a = torch::where(ok, cov / torch::where(ok, var, torch::ones_like(var)), torch::zeros_like(var));
  return a * (pred - mean_p) + mean_g;
}

torch::Tensor ScaleShiftInvariantLoss(const torch::Tensor& pred, const torch::Tensor& gt, const torch::Tensor& mask) {
  const torch::Tensor aligned = torch::clamp(AlignScaleShift(pred, gt, mask), kMinValidLevel, kMaxLevel);
  const torch::Tensor m = mask.to(torch::kFloat);
  const std::vector<int64_t> dims = {1, 2, 3};
  const torch::Tensor n = m.sum(dims);
  const torch::Tensor d = (torch::log(aligned) - torch::log(torch::clamp_min(gt, kMinValidLevel))) * m;
  const torch::Tensor has = (n > 0).to(torch::kFloat);
  // sqrt at 0 has an infinite derivative: a tiny floor keeps a perfect image's gradient finite.
  const torch::Tensor rmse = torch::sqrt(torch::clamp_min((d * d).sum(dims) / torch::clamp_min(n, 1.0), 1e-12)) * has;
  return rmse.sum() / torch::clamp_min(has.sum(), 1.0) * 10.0;
}

torch::Tensor PhotoBatch(const std::vector<const ImageF*>& photos) {
  CANDI_CHECK(!photos.empty());
  const int w = photos[0]->width(), h = photos[0]->height();
  torch::Tensor t = torch::empty({static_cast<int64_t>(photos.size()), 1, h, w});
  float* out = t.data_ptr<float>();
  for (const ImageF* p : photos) {
    CANDI_CHECK(p->width() == w && p->height() == h && p->channels() == 1);
    for (float v : p->values()) *out++ = ((std::isfinite(v) ? v : 0.5f) - 0.5f) / 0.25f;
  }
  return t;
}

BtsNetImpl::BtsNetImpl(const NetOptions& o) : options(o) {
  o.Check();
  const int g = o.growth, F = o.decoder_width;
  int c = 2 * g;
  encoder_stem = register_module("stem", nn::Sequential(Conv(1, c, 7, 2), nn::BatchNorm2d(c), nn::ReLU()));
  pool0 = register_module("pool0", nn::MaxPool2d(nn::MaxPool2dOptions(3).stride(2).padding(1)));
  std::vector<int> skip = {c, c};  // channels at 1/2, 1/4, then 1/8, 1/16
  for (int b = 0; b < 4; ++b) {
    nn::Sequential block;
    for (int l = 0; l < o.blocks[b]; ++l, c += g) block->push_back(DenseLayer(c, g));
    blocks.push_back(register_module("block" + std::to_string(b + 1), block));
    if (b == 3) break;
    transitions.push_back(register_module(
        "transition" + std::to_string(b + 1),
        nn::Sequential(nn::BatchNorm2d(c), nn::ReLU(), Conv(c, c / 2, 1),
                       nn::AvgPool2d(nn::AvgPool2dOptions(2).stride(2)))));
    c /= 2;
    skip.push_back(c);
  }
  norm5 = register_module("norm5", nn::Sequential(nn::BatchNorm2d(c), nn::ReLU()));
  decoder = register_module("decoder", nn::ModuleDict());
  auto add = [&](const std::string& name, std::shared_ptr<nn::Module> m) { decoder->update({{name, m}}); };
  add("upconv5", Upconv(c, F).ptr());
  add("bn5", nn::BatchNorm2d(F).ptr());
  add("conv5", ConvElu(F + skip[3], F).ptr());
  add("upconv4", Upconv(F, F / 2).ptr());
  add("bn4", nn::BatchNorm2d(F / 2).ptr());
  add("conv4", ConvElu(F / 2 + skip[2], F / 2).ptr());
  add("bn4_2", nn::BatchNorm2d(F / 2).ptr());
  const int base = F / 2 + skip[2];
  add("daspp_3", Atrous(F / 2, F / 4, 3, false).ptr());
  add("daspp_6", Atrous(base + F / 4, F / 4, 6, true).ptr());
  add("daspp_12", Atrous(base + F / 2, F / 4, 12, true).ptr());
  add("daspp_18", Atrous(base + 3 * F / 4, F / 4, 18, true).ptr());
  add("daspp_24", Atrous(base + F, F / 4, 24, true).ptr());
  add("daspp_conv", ConvElu(F / 2 + 5 * (F / 4), F / 4).ptr());
  add("reduc8x8", Reduction(F / 4, F / 4, false).ptr());
  add("upconv3", Upconv(F / 4, F / 4).ptr());
  add("bn3", nn::BatchNorm2d(F / 4).ptr());
  add("conv3", ConvElu(F / 4 + skip[1] + 1, F / 4).ptr());
  add("reduc4x4", Reduction(F / 4, F / 8, false).ptr());
  add("upconv2", Upconv(F / 4, F / 8).ptr());
  add("bn2", nn::BatchNorm2d(F / 8).ptr());
  add("conv2", ConvElu(F / 8 + skip[0] + 1, F / 8).ptr());
  add("reduc2x2", Reduction(F / 8, F / 16, false).ptr());
  add("upconv1", Upconv(F / 8, F / 16).ptr());
  add("reduc1x1", Reduction(F / 16, F / 32, true).ptr());
  add("conv1", ConvElu(F / 16 + 4, F / 16).ptr());
  add("get_depth", nn::Sequential(Conv(F / 16, 1, 3), nn::Sigmoid()).ptr());
}

torch::Tensor BtsNetImpl::forward(const torch::Tensor& x) {
  CANDI_CHECK(x.dim() == 4 && x.size(2) % 32 == 0 && x.size(3) % 32 == 0) << x.sizes();
  auto run = [&](const char* name, const torch::Tensor& t) {
    const auto m = decoder[name];
    if (auto s = std::dynamic_pointer_cast<nn::SequentialImpl>(m)) return s->forward(t);
    return std::dynamic_pointer_cast<nn::BatchNorm2dImpl>(m)->forward(t);
  };
  const torch::Tensor skip0 = encoder_stem->forward(x);  // 1/2
  const torch::Tensor skip1 = pool0->forward(skip0);     // 1/4
  const torch::Tensor skip2 = transitions[0]->forward(blocks[0]->forward(skip1));  // 1/8
  const torch::Tensor skip3 = transitions[1]->forward(blocks[1]->forward(skip2));  // 1/16
  const torch::Tensor dense = norm5->forward(blocks[3]->forward(transitions[2]->forward(blocks[2]->forward(skip3))));
  const double D = options.max_depth;

  const torch::Tensor iconv5 = run("conv5", torch::cat({run("bn5", run("upconv5", dense)), skip3}, 1));
  const torch::Tensor concat4 = torch::cat({run("bn4", run("upconv4", iconv5)), skip2}, 1);
  const torch::Tensor iconv4 = run("bn4_2", run("conv4", concat4));
  std::vector<torch::Tensor> daspp = {run("daspp_3", iconv4)};
  torch::Tensor cat = torch::cat({concat4, daspp.back()}, 1);
  for (const char* name : {"daspp_6", "daspp_12", "daspp_18", "daspp_24"}) {
    daspp.push_back(run(name, cat));
    cat = torch::cat({cat, daspp.back()}, 1);
  }
  daspp.insert(daspp.begin(), iconv4);
  const torch::Tensor daspp_feat = run("daspp_conv", torch::cat(daspp, 1));

  const torch::Tensor depth8 = LocalPlanarGuidance(PlaneFromRaw(run("reduc8x8", daspp_feat), D), 8).unsqueeze(1) / D;
  const torch::Tensor iconv3 = run("conv3", torch::cat({run("bn3", run("upconv3", daspp_feat)), skip1, Every(depth8, 4)}, 1));
  const torch::Tensor depth4 = LocalPlanarGuidance(PlaneFromRaw(run("reduc4x4", iconv3), D), 4).unsqueeze(1) / D;
  const torch::Tensor iconv2 = run("conv2", torch::cat({run("bn2", run("upconv2", iconv3)), skip0, Every(depth4, 2)}, 1));
  const torch::Tensor depth2 = LocalPlanarGuidance(PlaneFromRaw(run("reduc2x2", iconv2), D), 2).unsqueeze(1) / D;
  const torch::Tensor upconv1 = run("upconv1", iconv2);
  const torch::Tensor iconv1 = run("conv1", torch::cat({upconv1, run("reduc1x1", upconv1), depth2, depth4, depth8}, 1));
  return D * run("get_depth", iconv1);
}

void WriteModelArchive(const DepthModel::Impl& impl, torch::serialize::OutputArchive* archive) {
  const NetOptions& o = impl.net->options;
  archive->write("candi_relief_version", torch::tensor(kModelVersion));
  archive->write("growth", torch::tensor(static_cast<int64_t>(o.growth)));
  archive->write("blocks", torch::tensor(std::vector<int64_t>(o.blocks.begin(), o.blocks.end())));
  archive->write("decoder_width", torch::tensor(static_cast<int64_t>(o.decoder_width)));
  archive->write("max_depth", torch::tensor(o.max_depth, torch::kFloat64));
  archive->write("pixels_per_m", torch::tensor(impl.pixels_per_m, torch::kFloat64));
  // Written only when set: an absolute model's file keeps the bytes it had before the key existed.
  if (o.relative) archive->write("relative", torch::tensor(static_cast<int64_t>(1)));
  torch::serialize::OutputArchive net;
  impl.net->save(net);
  archive->write("net", net);
}

torch::Tensor ReadTensor(torch::serialize::InputArchive& archive, const char* key) {
  // A fresh tensor each time: read() into a defined tensor keeps that tensor's dtype and
  // reinterprets the bytes (an int64 then read as a double gave 4.6e18).
  torch::Tensor t;
  archive.read(key, t);
  return t;
}

std::shared_ptr<DepthModel::Impl> ReadModelArchive(torch::serialize::InputArchive& archive) {
  torch::Tensor t = ReadTensor(archive, "candi_relief_version");
  CANDI_CHECK(t.item<int64_t>() == kModelVersion) << "model version " << t.item<int64_t>();
  NetOptions o;
  t = ReadTensor(archive, "growth");
  o.growth = static_cast<int>(t.item<int64_t>());
  t = ReadTensor(archive, "blocks");
  o.blocks.clear();
  for (int64_t i = 0; i < t.numel(); ++i) o.blocks.push_back(static_cast<int>(t[i].item<int64_t>()));
  t = ReadTensor(archive, "decoder_width");
  o.decoder_width = static_cast<int>(t.item<int64_t>());
  t = ReadTensor(archive, "max_depth");
  o.max_depth = t.item<double>();
  torch::Tensor relative;
  o.relative = archive.try_read("relative", relative) && relative.item<int64_t>() != 0;
  auto impl = std::make_shared<DepthModel::Impl>(o);
  t = ReadTensor(archive, "pixels_per_m");
  impl->pixels_per_m = t.item<double>();
  torch::serialize::InputArchive net;
  archive.read("net", net);
  impl->net->load(net);
  return impl;
}

void SaveArchive(torch::serialize::OutputArchive& archive, const std::string& path) {
  std::ostringstream bytes;
  archive.save_to(bytes);
  WriteFileAtomic(path, bytes.str());
}

DepthModel DepthModel::Create(const NetOptions& options, uint64_t seed) {
  options.Check();
  torch::manual_seed(seed);
  return DepthModel(std::make_shared<Impl>(options));
}

DepthModel DepthModel::Load(const std::string& path) {
  const std::string bytes = ReadFileToString(path);  // InputError for a missing file
  try {
    std::istringstream in(bytes);
    torch::serialize::InputArchive archive;
    archive.load_from(in);
    return DepthModel(ReadModelArchive(archive));
  } catch (const c10::Error& e) {
    throw InputError(path, "", std::string("not a candi relief model: ") + e.what_without_backtrace());
  } catch (const std::invalid_argument& e) {
    throw InputError(path, "", std::string("not a candi relief model: ") + e.what());
  } catch (const InternalError& e) {
    throw InputError(path, "", std::string("not a candi relief model: ") + e.what());
  }
}

void DepthModel::Save(const std::string& path) const {
  torch::serialize::OutputArchive archive;
  WriteModelArchive(*impl_, &archive);
  SaveArchive(archive, path);
}

const NetOptions& DepthModel::options() const { return impl_->net->options; }

int64_t DepthModel::ParameterCount() const {
  int64_t n = 0;
  for (const auto& p : impl_->net->parameters()) n += p.numel();
  return n;
}

double DepthModel::pixels_per_m() const { return impl_->pixels_per_m; }
void DepthModel::set_pixels_per_m(double value) {
  CANDI_CHECK(value > 0) << value;
  impl_->pixels_per_m = value;
}

void DepthModel::set_relative(bool relative) { impl_->net->options.relative = relative; }

ImageF DepthModel::PredictTile(const ImageF& tile) const {
  torch::NoGradGuard no_grad;
  impl_->net->eval();
  const torch::Tensor out = impl_->net->forward(PhotoBatch({&tile})).contiguous();
  ImageF depth(tile.width(), tile.height(), 1);
  std::copy(out.data_ptr<float>(), out.data_ptr<float>() + out.numel(), depth.data());
  return depth;
}

ImageF DepthModel::Predict(const PredictOptions& options, const ImageF& photo,
                           const ProgressCallback& progress) const {
  options.Check();
  CANDI_CHECK(photo.channels() == 1 && !photo.empty());
  ImageF input = photo;
  if (options.photo_pixels_per_m > 0) {
    const double s = impl_->pixels_per_m / options.photo_pixels_per_m;
    const int w = std::max(1, static_cast<int>(std::lround(photo.width() * s)));
    const int h = std::max(1, static_cast<int>(std::lround(photo.height() * s)));
    for (float& v : input.values()) v = std::isfinite(v) ? v : 0.5f;
    input = Resample(input, w, h);
  }
  ImageF depth;
  if (impl_->net->options.relative) {
    depth = PredictWhole(input);
    if (progress) progress(1, 1);
    if (options.stretch) depth = StretchRelative(depth);
  } else {
    depth = PredictTiled(options.tiles, input, [this](const ImageF& tile) { return PredictTile(tile); }, progress);
  }
  return Resample(depth, photo.width(), photo.height());
}

ImageF DepthModel::PredictWhole(const ImageF& image) const {
  const int w = image.width(), h = image.height();
  const int pw = (w + 31) / 32 * 32, ph = (h + 31) / 32 * 32;
  ImageF padded(pw, ph, 1);
  for (int y = 0; y < ph; ++y) {
    for (int x = 0; x < pw; ++x) padded.at(x, y) = image.at(std::min(x, w - 1), std::min(y, h - 1));
  }
  const ImageF out = PredictTile(padded);
  ImageF depth(w, h, 1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) depth.at(x, y) = out.at(x, y);
  }
  return depth;
}

ImageF StretchRelative(const ImageF& levels) {
  std::vector<float> finite;
  finite.reserve(levels.values().size());
  for (float v : levels.values()) {
    if (std::isfinite(v)) finite.push_back(v);
  }
  ImageF out = levels;
  if (finite.empty()) return out;
  auto at = [&finite](double q) {
    const size_t k = std::min(finite.size() - 1, static_cast<size_t>(q * (finite.size() - 1) + 0.5));
    std::nth_element(finite.begin(), finite.begin() + k, finite.end());
    return static_cast<double>(finite[k]);
  };
  const double lo = at(0.02), hi = at(0.98);
  // A flat prediction (no relief seen) becomes the middle level, not a division by zero.
  const double scale = hi - lo > 1e-6 * std::max(1.0, std::abs(hi)) ? (kMaxLevel - kMinValidLevel) / (hi - lo) : 0.0;
  for (float& v : out.values()) {
    const double level = scale > 0 ? kMinValidLevel + (v - lo) * scale : kMaxLevel / 2;
    v = std::isfinite(v) ? static_cast<float>(std::clamp(level, 0.0, kMaxLevel)) : v;
  }
  return out;
}

}  // namespace candi::relief

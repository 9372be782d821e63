// Tests of the relief network (libtorch, really trained; tiny sizes so the suite stays fast).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "reconstruction/relief/relief_dataset.h"
#include "reconstruction/relief/relief_image.h"
#include "reconstruction/relief/relief_metrics.h"
#include "reconstruction/relief/relief_net.h"
#include "reconstruction/relief/relief_net_internal.h"
#include "reconstruction/relief/relief_synth.h"
#include "reconstruction/relief/relief_train.h"
#include "tests/util/test_util.h"

namespace candi::relief {
namespace {

NetOptions Tiny() {
  NetOptions o;
  o.growth = 4;
  o.blocks = {1, 1, 2, 1};
  o.decoder_width = 32;
  return o;
}

std::vector<TrainingPair> Patches(uint64_t seed, int panels) {
  SynthOptions s;
  s.width = 192;
  s.seed = seed;
  PatchOptions p;
  p.patch = 64;
  p.stride = 32;
  std::vector<TrainingPair> out;
  for (int i = 0; i < panels; ++i) {
    SynthPanel panel = SynthesizePanel(s, i);
    for (auto& pair : CutPatches(p, {panel.photo.photo, panel.depth})) out.push_back(std::move(pair));
  }
  return out;
}

TEST(Lpg, FrontoParallelPlaneGivesConstantDepth) {
  // Normal (0, 0, 1), distance 100: depth 100 at every pixel of every patch.
  const torch::Tensor plane = torch::tensor({0.0f, 0.0f, 1.0f, 100.0f}).view({1, 4, 1, 1}).repeat({2, 1, 3, 2});
  const torch::Tensor d = LocalPlanarGuidance(plane, 8);
  ASSERT_EQ(d.sizes(), (std::vector<int64_t>{2, 24, 16}));
  EXPECT_NEAR(d.min().item<float>(), 100.0f, 1e-4);
  EXPECT_NEAR(d.max().item<float>(), 100.0f, 1e-4);
}

TEST(Lpg, TiltedPlaneMatchesHandComputation) {
  // n = (0.3, -0.2, sqrt(0.87)), n4 = 50, ratio 4: pixel (col 3, row 0) of the patch has
  // u = (3 - 1.5) / 4 = 0.375, v = (0 - 1.5) / 4 = -0.375.
  const float n3 = std::sqrt(0.87f);
  const torch::Tensor plane = torch::tensor({0.3f, -0.2f, n3, 50.0f}).view({1, 4, 1, 1});
  const torch::Tensor d = LocalPlanarGuidance(plane, 4);
  const float expected = 50.0f / (0.3f * 0.375f + (-0.2f) * (-0.375f) + n3);
  EXPECT_NEAR(d[0][0][3].item<float>(), expected, 1e-4);
  const float centre_left = 50.0f / (0.3f * -0.375f + (-0.2f) * 0.125f + n3);  // col 0, row 2
  EXPECT_NEAR(d[0][2][0].item<float>(), centre_left, 1e-4);
}

TEST(Lpg, DenominatorStaysPositiveForAnyRawPlane) {
  // Extreme raw values push theta to its limit (pi/6) in every direction phi.
  const torch::Tensor raw = torch::stack({torch::full({64}, 30.0f), torch::linspace(-30, 30, 64),
                                          torch::full({64}, 0.0f)}).view({1, 3, 8, 8});
  const torch::Tensor plane = PlaneFromRaw(raw, 255);
  const torch::Tensor u = torch::tensor({-0.4375f, 0.4375f});
  const torch::Tensor n1 = plane.select(1, 0), n2 = plane.select(1, 1), n3 = plane.select(1, 2);
  for (float a : {-0.4375f, 0.4375f}) {
    for (float b : {-0.4375f, 0.4375f}) {
      EXPECT_GT((n1 * a + n2 * b + n3).min().item<float>(), 0.5f);
    }
  }
  EXPECT_TRUE(torch::isfinite(LocalPlanarGuidance(plane, 8)).all().item<bool>());
}

TEST(SilogLoss, ZeroAtGroundTruthMaskedAndScaleInvariantPart) {
  const torch::Tensor gt = torch::rand({2, 1, 8, 8}) * 200 + 10;
  const torch::Tensor all = torch::ones_like(gt, torch::kBool);
  EXPECT_NEAR(SilogLoss(gt, gt, all).item<float>(), 0.0f, 1e-3);
  // A pure scale error costs only sqrt(0.15) |ln s| x 10.
  EXPECT_NEAR(SilogLoss(gt * 2, gt, all).item<float>(), 10 * std::sqrt(0.15) * std::log(2.0), 1e-3);
  // Wrong values where the mask is off do not count.
  torch::Tensor pred = gt.clone();
  pred.index_put_({0, 0, 0, 0}, 1000.0f);
  torch::Tensor mask = all.clone();
  mask.index_put_({0, 0, 0, 0}, false);
  EXPECT_NEAR(SilogLoss(pred, gt, mask).item<float>(), 0.0f, 1e-3);
  const torch::Tensor none = torch::zeros_like(gt, torch::kBool);
  EXPECT_EQ(SilogLoss(pred, gt, none).item<float>(), 0.0f);
}

// The scale-and-shift-invariant loss: zero for any a gt + b (a != 0), masked pixels ignored,
// an image without known pixels left out, a flat prediction finite, and it grows with a
// structural error that no scale and offset can undo.
TEST(ScaleShiftInvariantLoss, InvariantToScaleAndOffsetAndMasked) {
  torch::manual_seed(4);
  const torch::Tensor gt = torch::rand({2, 1, 16, 16}) * 200 + 10;
  const torch::Tensor all = torch::ones_like(gt, torch::kBool);
  EXPECT_NEAR(ScaleShiftInvariantLoss(gt, gt, all).item<float>(), 0.0f, 2e-3);
  EXPECT_NEAR(ScaleShiftInvariantLoss(gt * 0.01 - 3, gt, all).item<float>(), 0.0f, 2e-3);
  EXPECT_NEAR(ScaleShiftInvariantLoss(1000 - gt * 7, gt, all).item<float>(), 0.0f, 2e-3);
  // The alignment is exact at survey-like magnitudes: levels offset by 10^5.
  EXPECT_NEAR(ScaleShiftInvariantLoss(gt + 1e5, gt, all).item<float>(), 0.0f, 0.05);
  torch::Tensor pred = gt.clone();
  pred.index_put_({0, 0, 3, 3}, 5000.0f);
  torch::Tensor mask = all.clone();
  mask.index_put_({0, 0, 3, 3}, false);
  EXPECT_NEAR(ScaleShiftInvariantLoss(pred, gt, mask).item<float>(), 0.0f, 2e-3);
  EXPECT_GT(ScaleShiftInvariantLoss(pred, gt, all).item<float>(), 0.1f);
  // Image 1 without any known pixel: the loss is image 0's alone, not halved.
  torch::Tensor half = all.clone();
  half.index_put_({1}, false);
  const torch::Tensor noisy = gt + torch::randn_like(gt) * 20;
  const float both_img0 = ScaleShiftInvariantLoss(noisy.narrow(0, 0, 1), gt.narrow(0, 0, 1), all.narrow(0, 0, 1)).item<float>();
  EXPECT_NEAR(ScaleShiftInvariantLoss(noisy, gt, half).item<float>(), both_img0, 1e-4);
  EXPECT_EQ(ScaleShiftInvariantLoss(noisy, gt, torch::zeros_like(all)).item<float>(), 0.0f);
  // A flat prediction: finite loss and finite gradient (the fit has no scale to take).
  torch::Tensor flat = torch::full_like(gt, 77.0).requires_grad_(true);
  const torch::Tensor l = ScaleShiftInvariantLoss(flat, gt, all);
  l.backward();
  EXPECT_TRUE(std::isfinite(l.item<float>()) && l.item<float>() > 0);
  EXPECT_TRUE(torch::isfinite(flat.grad()).all().item<bool>());
  // A structural error costs, whatever its scale.
  const torch::Tensor flipped = torch::flip(gt, {3});
  EXPECT_NEAR(ScaleShiftInvariantLoss(flipped * 3 + 1, gt, all).item<float>(),
              ScaleShiftInvariantLoss(flipped, gt, all).item<float>(), 1e-3);
  EXPECT_GT(ScaleShiftInvariantLoss(flipped, gt, all).item<float>(), 1.0f);
}

// A relative model: trained with the scale-and-shift-invariant loss to the byte on one thread,
// saved and loaded as relative, predicting whole images; its stretched output spans the levels,
// and an absolute model's file does not change by the new key.
TEST(DepthModel, RelativeModelTrainsReproduciblyAndPredictsWholeImages) {
  SetTorchThreads(1);
  testing::TempDir dir;
  DepthModel::Create(Tiny(), 21).Save(dir.File("base.pt"));
  const std::vector<TrainingPair> train = Patches(6, 1);
  auto tune = [&](const std::string& out, double* loss_before, double* loss_after) {
    DepthModel m = DepthModel::Load(dir.File("base.pt"));
    EXPECT_FALSE(m.options().relative);
    m.set_relative(true);
    if (loss_before) *loss_before = EvaluateLoss(m, train);
    TrainOptions o;
    o.epochs = 4;
    o.batch = 2;
    o.seed = 5;
    o.edge_weight = 1;
    TrainDepthModel(o, train, {}, &m);
    if (loss_after) *loss_after = EvaluateLoss(m, train);
    m.Save(dir.File(out));
    return testing::ReadBytes(dir.File(out));
  };
  double before = 0, after = 0;
  const std::string a = tune("a.pt", &before, &after), b = tune("b.pt", nullptr, nullptr);
  EXPECT_EQ(a, b);
  EXPECT_LT(after, before) << "the scale-and-shift-invariant loss falls";
  const DepthModel rel = DepthModel::Load(dir.File("a.pt"));
  EXPECT_TRUE(rel.options().relative);
  // The absolute model's file is the same bytes after a load and save.
  DepthModel::Load(dir.File("base.pt")).Save(dir.File("again.pt"));
  EXPECT_EQ(testing::ReadBytes(dir.File("again.pt")), testing::ReadBytes(dir.File("base.pt")));
  // Whole images: any size, equal to one pass over the edge-padded image, whatever the tiles say.
  SynthOptions s;
  s.width = 150;
  s.seed = 31;
  const ImageF photo = SynthesizePanel(s, 0).photo.photo;
  PredictOptions raw;
  raw.stretch = false;
  raw.tiles.tile = 32;
  raw.tiles.overlap = 8;
  const ImageF whole = rel.Predict(raw, photo);
  EXPECT_EQ(whole.values(), rel.PredictWhole(photo).values());
  ImageF padded(160, ((photo.height() + 31) / 32) * 32, 1);
  for (int y = 0; y < padded.height(); ++y) {
    for (int x = 0; x < 160; ++x) padded.at(x, y) = photo.at(std::min(x, photo.width() - 1), std::min(y, photo.height() - 1));
  }
  const ImageF one = rel.PredictTile(padded);
  for (int y = 0; y < photo.height(); y += 7) {
    for (int x = 0; x < photo.width(); x += 7) ASSERT_EQ(whole.at(x, y), one.at(x, y)) << x << "," << y;
  }
  const ImageF stretched = rel.Predict(PredictOptions(), photo);
  std::vector<float> v = stretched.values();
  std::sort(v.begin(), v.end());
  EXPECT_NEAR(v[static_cast<size_t>(0.02 * (v.size() - 1) + 0.5)], kMinValidLevel, 1e-3);
  EXPECT_NEAR(v[static_cast<size_t>(0.98 * (v.size() - 1) + 0.5)], kMaxLevel, 1e-3);
  EXPECT_GE(v.front(), 0.0f);
  EXPECT_LE(v.back(), kMaxLevel);
  // Hard photos: flat, saturated, tiny, with NaN: finite levels in range, the photo's size.
  ImageF nan_photo(50, 40, 1, 0.5f);
  nan_photo.at(3, 3) = NAN;
  for (const ImageF& hard : {ImageF(70, 33, 1, 0.0f), ImageF(70, 33, 1, 1.0f), ImageF(20, 9, 1, 0.3f), nan_photo}) {
    const ImageF d = rel.Predict(PredictOptions(), hard);
    ASSERT_EQ(d.width(), hard.width());
    ASSERT_EQ(d.height(), hard.height());
    for (float level : d.values()) ASSERT_TRUE(std::isfinite(level) && level >= 0 && level <= kMaxLevel) << level;
  }
}

TEST(StretchRelative, FlatAndNonFiniteImages) {
  ImageF flat(10, 10, 1, 3.0f);
  const ImageF flat_out = StretchRelative(flat);
  for (float v : flat_out.values()) EXPECT_EQ(v, static_cast<float>(kMaxLevel / 2));
  ImageF ramp(100, 1, 1);
  for (int x = 0; x < 100; ++x) ramp.at(x, 0) = 1e6f + x * 0.5f;  // large values, fine steps
  ramp.at(50, 0) = NAN;
  const ImageF out = StretchRelative(ramp);
  EXPECT_TRUE(std::isnan(out.at(50, 0)));
  for (int x = 1; x < 100; ++x) {
    if (x != 50 && x != 51) {
      EXPECT_GE(out.at(x, 0), out.at(x - 1, 0)) << x;
    }
  }
  EXPECT_EQ(out.at(0, 0), 0.0f);
  EXPECT_EQ(out.at(99, 0), static_cast<float>(kMaxLevel));
  EXPECT_TRUE(std::isnan(StretchRelative(ImageF(4, 4, 1, NAN)).values()[0]));
}

TEST(DepthModel, TrainingLowersTheLossAndSavedModelsReloadExactly) {
  const auto train = Patches(5, 2);
  ASSERT_GE(train.size(), 8u);
  SetTorchThreads(1);
  DepthModel model = DepthModel::Create(Tiny(), 3);
  const double before = EvaluateLoss(model, train);
  TrainOptions o;
  o.epochs = 6;
  o.batch = 4;
  o.augment.rotate_probability = o.augment.flip_probability = o.augment.brightness_probability = 0;
  testing::TempDir dir;
  o.checkpoint = dir.File("ckpt.pt");
  int reports = 0;
  const TrainSummary s = TrainDepthModel(o, train, {train[0]}, &model, [&](const EpochReport& r) {
    ++reports;
    EXPECT_GT(r.validation.count, 0);
  });
  EXPECT_EQ(reports, 6);
  EXPECT_FALSE(s.stopped_early);
  const double after = EvaluateLoss(model, train);
  EXPECT_LT(after, before * 0.95) << before << " -> " << after;
  model.Save(dir.File("m.pt"));
  const DepthModel back = DepthModel::Load(dir.File("m.pt"));
  EXPECT_EQ(back.ParameterCount(), model.ParameterCount());
  EXPECT_EQ(back.PredictTile(train[1].photo).values(), model.PredictTile(train[1].photo).values());
  // Resume: the checkpoint says 6 epochs are done; asking for 7 runs exactly one more.
  o.epochs = 7;
  o.resume = true;
  DepthModel resumed = DepthModel::Create(Tiny(), 99);
  const TrainSummary r = TrainDepthModel(o, train, {}, &resumed);
  EXPECT_EQ(r.epochs.size(), 1u);
  EXPECT_EQ(r.epochs[0].epoch, 7);
  EXPECT_EQ(r.steps, s.steps + static_cast<int64_t>((train.size() + 3) / 4));
  EXPECT_THROW(DepthModel::Load(dir.File("missing.pt")), InputError);
  testing::WriteBytes(dir.File("junk.pt"), "not a model");
  EXPECT_THROW(DepthModel::Load(dir.File("junk.pt")), InputError);
}

// Fine-tuning: a saved model trained on with a fresh optimiser. The same seed gives the same
// bytes of weights (one thread); the edge term changes what is learnt, and is finite on patches
// whose depth is partly unknown.
TEST(DepthModel, FineTuningIsReproducibleToTheByteAndTheEdgeTermTakesEffect) {
  SetTorchThreads(1);
  testing::TempDir dir;
  DepthModel::Create(Tiny(), 21).Save(dir.File("base.pt"));
  std::vector<TrainingPair> train = Patches(6, 1);
  ASSERT_GE(train.size(), 4u);
  for (int y = 0; y < 20; ++y) {
    for (int x = 0; x < 64; ++x) train[0].depth.at(x, y) = 0;  // unknown, as on a photograph
  }
  auto tune = [&](double edge_weight, const std::string& out) {
    DepthModel m = DepthModel::Load(dir.File("base.pt"));
    TrainOptions o;
    o.epochs = 2;
    o.batch = 2;
    o.learning_rate = 3e-4;
    o.end_learning_rate = 1e-4;
    o.seed = 5;
    o.edge_weight = edge_weight;
    const TrainSummary s = TrainDepthModel(o, train, {}, &m);
    for (const EpochReport& r : s.epochs) EXPECT_TRUE(std::isfinite(r.loss)) << r.epoch;
    m.Save(dir.File(out));
    return testing::ReadBytes(dir.File(out));
  };
  const std::string a = tune(0, "a.pt"), b = tune(0, "b.pt"), e = tune(1, "e.pt"), f = tune(1, "f.pt");
  EXPECT_EQ(a, b);
  EXPECT_EQ(e, f);
  EXPECT_NE(a, e);
  EXPECT_NE(a, testing::ReadBytes(dir.File("base.pt")));
  TrainOptions bad;
  bad.edge_weight = -1;
  EXPECT_THROW(bad.Check(), std::invalid_argument);
}

class TrainedTiny : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    SetTorchThreads(1);
    model_ = new DepthModel(DepthModel::Create(Tiny(), 11));
    TrainOptions o;
    o.epochs = 3;
    o.batch = 4;
    TrainDepthModel(o, Patches(9, 2), {}, model_);
  }
  static void TearDownTestSuite() { delete model_; }
  static DepthModel* model_;
};
DepthModel* TrainedTiny::model_ = nullptr;

TEST_F(TrainedTiny, TiledEqualsOnePassAwayFromBordersAndShowsNoSeams) {
  SynthOptions s;
  s.width = 320;
  s.seed = 77;
  const SynthPanel panel = SynthesizePanel(s, 0);
  const ImageF photo = Resample(panel.photo.photo, 320, 96);  // one-pass needs multiples of 32
  const ImageF gt = Resample(panel.depth, 320, 96);
  const ImageF whole = model_->PredictTile(photo);
  PredictOptions o;
  o.tiles.tile = 64;
  o.tiles.overlap = 24;
  const ImageF tiled = model_->Predict(o, photo);
  double diff = 0, n = 0;
  for (int y = 16; y < 80; ++y) {
    for (int x = 16; x < 304; ++x) diff += std::abs(tiled.at(x, y) - whole.at(x, y)), ++n;
  }
  EXPECT_LT(diff / n, 6.0) << "mean |tiled - one pass| in levels, away from the borders";
  // The error against the truth near tile borders is no larger than elsewhere.
  const std::vector<int> xs = TileStarts(320, 64, 24);
  auto near_border = [&](int x) {
    for (size_t i = 1; i < xs.size(); ++i) {
      if (std::abs(x - xs[i]) <= 2 || std::abs(x - (xs[i - 1] + 64)) <= 2) return true;
    }
    return false;
  };
  double e_border = 0, n_border = 0, e_rest = 0, n_rest = 0, jump_border = 0, jump_rest = 0;
  for (int y = 0; y < 96; ++y) {
    for (int x = 0; x + 1 < 320; ++x) {
      const double e = std::abs(tiled.at(x, y) - gt.at(x, y));
      const double j = std::abs(tiled.at(x + 1, y) - tiled.at(x, y));
      (near_border(x) ? e_border : e_rest) += e;
      (near_border(x) ? jump_border : jump_rest) += j;
      (near_border(x) ? n_border : n_rest) += 1;
    }
  }
  EXPECT_LE(e_border / n_border, 1.15 * e_rest / n_rest);
  EXPECT_LE(jump_border / n_border, 1.15 * jump_rest / n_rest) << "no seam at tile borders";
}

TEST_F(TrainedTiny, HardPhotosGiveFiniteDepthInRange) {
  PredictOptions o;
  o.tiles.tile = 64;
  o.tiles.overlap = 16;
  ImageF nan_photo(50, 40, 1, 0.5f);
  nan_photo.at(3, 3) = NAN;
  for (const ImageF& photo : {ImageF(70, 33, 1, 0.0f), ImageF(70, 33, 1, 1.0f), ImageF(70, 33, 1, 0.42f),
                              ImageF(20, 9, 1, 0.3f), nan_photo}) {
    const ImageF d = model_->Predict(o, photo);
    ASSERT_EQ(d.width(), photo.width());
    ASSERT_EQ(d.height(), photo.height());
    for (float v : d.values()) ASSERT_TRUE(std::isfinite(v) && v >= 0 && v <= 255) << v;
  }
  // At another resolution: resampled in and out.
  o.photo_pixels_per_m = model_->pixels_per_m() * 2;
  EXPECT_EQ(model_->Predict(o, ImageF(130, 70, 1, 0.5f)).width(), 130);
}

}  // namespace
}  // namespace candi::relief

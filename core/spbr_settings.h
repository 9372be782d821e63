// What makes an SPBR image besides the data and the camera, declared once and embedded by every
// renderer (render/), the opacity law (sampling/), the pipeline's renders and sections, the scene
// file, the viewer and its picks, and a published site's default view:
//
// - SpbrSettings: the repeat level L (ensembles averaged), the seed of the ensemble assignment,
//   the point size and whether the view is opaque. "Opaque" draws every point once, as one
//   ensemble: EffectiveRepeatLevel() is 1 and point multiplicities are ignored.
// - Brightness: how the averaged image is lifted: automatically (Uchida et al.'s rule,
//   render::AutoBrightnessGain), not at all ("none", a gain of 1), or by a fixed gain. One parser
//   for the scene file, the command line, the viewer's messages and view files.
// - ImageSettings: those two with the image's size and background: what a build's scene renders
//   with, what its record keeps (render/build_record.h) and what candi render draws.
//
// Plain values, thread-compatible. Check() throws std::invalid_argument naming the field.
#pragma once

#include <cstdint>
#include <string>

#include "core/point_cloud.h"

namespace candi {

inline constexpr int kMaxRepeatLevel = 100000;

struct SpbrSettings {
  int repeat_level = 100;   // L, ensembles averaged, [1, kMaxRepeatLevel]
  uint64_t seed = 1;        // seeds each point's ensemble (and opacity control's rounding)
  double point_size = 1.0;  // pixels, [1, 64] (stochastic rounding of fractional sizes)
  bool opaque = false;      // one ensemble of every point: L = 1, multiplicities ignored
  // L as drawn: 1 when opaque.
  int EffectiveRepeatLevel() const { return opaque ? 1 : repeat_level; }
  void Check() const;
  bool operator==(const SpbrSettings& o) const {
    return repeat_level == o.repeat_level && seed == o.seed && point_size == o.point_size &&
           opaque == o.opaque;
  }
  bool operator!=(const SpbrSettings& o) const { return !(*this == o); }
};

class Brightness {
 public:
  static constexpr double kMaxGain = 100;  // a fixed gain is in (0, kMaxGain]

  Brightness() = default;  // automatic
  static Brightness Auto() { return Brightness(); }
  static Brightness None() { return Brightness(Kind::kNone, 1.0); }
  // A fixed gain in (0, kMaxGain]; std::invalid_argument otherwise.
  static Brightness Gain(double gain);
  // "auto", "none" or a gain in (0, kMaxGain] as decimal text; std::invalid_argument saying what
  // is expected otherwise.
  static Brightness Parse(const std::string& text);
  // The rule Parse and Gain enforce, for messages: "auto, none or a gain in (0, 100]".
  static const char* Rule();

  bool automatic() const { return kind_ == Kind::kAuto; }
  bool none() const { return kind_ == Kind::kNone; }
  // The fixed gain: 1 for none; for automatic, 1 (the gain before the image is known).
  double gain() const { return gain_; }
  // -1 for automatic, else the gain: the compact number a view's settings carry (none is 1).
  double AsNumber() const { return automatic() ? -1.0 : gain_; }
  // "auto", "none" or the gain in the shortest text that reads back to it.
  std::string ToString() const;

  bool operator==(const Brightness& o) const { return kind_ == o.kind_ && gain_ == o.gain_; }
  bool operator!=(const Brightness& o) const { return !(*this == o); }

 private:
  enum class Kind { kAuto, kNone, kGain };
  Brightness(Kind kind, double gain) : kind_(kind), gain_(gain) {}
  Kind kind_ = Kind::kAuto;
  double gain_ = 1.0;
};

struct ImageSettings {
  SpbrSettings spbr;
  int width = 1024, height = 768;  // pixels, [1, kMaxImageSize]
  Rgb8 background{0, 0, 0};
  Brightness brightness;
  void Check() const;
  bool operator==(const ImageSettings& o) const {
    return spbr == o.spbr && width == o.width && height == o.height && background == o.background &&
           brightness == o.brightness;
  }
};
inline constexpr int kMaxImageSize = 16384;

}  // namespace candi

#include "core/spbr_settings.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include "core/check.h"
#include "core/text_format.h"

namespace candi {

void SpbrSettings::Check() const {
  CANDI_CHECK_OPTION(repeat_level >= 1 && repeat_level <= kMaxRepeatLevel, repeat_level,
                     "in [1, 100000]");
  static_assert(kMaxRepeatLevel == 100000, "the rule above says 100000");
  CANDI_CHECK_OPTION(point_size >= 1 && point_size <= 64, point_size, "in [1, 64]");
}

void ImageSettings::Check() const {
  spbr.Check();
  CANDI_CHECK_OPTION(width >= 1 && width <= kMaxImageSize, width, "in [1, 16384]");
  CANDI_CHECK_OPTION(height >= 1 && height <= kMaxImageSize, height, "in [1, 16384]");
  static_assert(kMaxImageSize == 16384, "the rules above say 16384");
}

const char* Brightness::Rule() { return "auto, none or a gain in (0, 100]"; }

Brightness Brightness::Gain(double gain) {
  if (!(gain > 0 && gain <= kMaxGain)) {
    throw std::invalid_argument("brightness " + FormatDouble(gain) + ": expected " + Rule());
  }
  return Brightness(Kind::kGain, gain);
}

Brightness Brightness::Parse(const std::string& text) {
  if (text == "auto") return Auto();
  if (text == "none") return None();
  const char* begin = text.c_str();
  char* end = nullptr;
  errno = 0;
  const double gain = std::strtod(begin, &end);
  const bool decimal =
      !text.empty() && text.find_first_not_of("0123456789.eE+-") == std::string::npos;
  if (!decimal || end != begin + text.size() || errno != 0 || !(gain > 0 && gain <= kMaxGain)) {
    throw std::invalid_argument("'" + text + "': expected " + Rule());
  }
  return Brightness(Kind::kGain, gain);
}

std::string Brightness::ToString() const {
  switch (kind_) {
    case Kind::kAuto:
      return "auto";
    case Kind::kNone:
      return "none";
    case Kind::kGain:
      break;
  }
  return FormatDouble(gain_);
}

}  // namespace candi

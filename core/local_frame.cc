#include "core/local_frame.h"

#include <charconv>
#include <cmath>
#include <stdexcept>

#include "core/box.h"
#include "core/text_format.h"

namespace candi {

LocalFrame LocalFrame::Auto(const Box3d& world_box) {
  LocalFrame frame;
  if (world_box.IsEmpty()) return frame;
  const double magnitude = world_box.min.cwiseAbs().cwiseMax(world_box.max.cwiseAbs()).maxCoeff();
  if (magnitude < kAutoShiftThreshold) return frame;
  const Eigen::Vector3d center = world_box.Center();
  for (int k = 0; k < 3; ++k) frame.origin[k] = 100.0 * std::round(center[k] / 100.0);
  return frame;
}

std::string LocalFrame::ToString() const {
  return FormatDouble(origin.x()) + "," + FormatDouble(origin.y()) + "," +
         FormatDouble(origin.z());
}

LocalFrame ParseShift(const std::string& text) {
  LocalFrame frame;
  const char* p = text.data();
  const char* end = p + text.size();
  for (int k = 0; k < 3; ++k) {
    if (k > 0) {
      if (p == end || *p != ',') {
        throw std::invalid_argument("shift '" + text + "': expected three numbers x,y,z");
      }
      ++p;
    }
    double value = 0.0;
    auto [next, ec] = std::from_chars(p, end, value);
    if (ec != std::errc() || !std::isfinite(value)) {
      throw std::invalid_argument("shift '" + text + "': component " + std::to_string(k + 1) +
                                  " is not a finite number");
    }
    frame.origin[k] = value;
    p = next;
  }
  if (p != end) throw std::invalid_argument("shift '" + text + "': trailing characters");
  return frame;
}

}  // namespace candi

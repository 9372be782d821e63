#include "apps/arg_parse.h"

#include <charconv>
#include <cmath>
#include <stdexcept>

namespace candi::app {

std::vector<double> ParseNumbers(const std::string& text, char separator, const std::string& what) {
  std::vector<double> out;
  const char* p = text.data();
  const char* end = p + text.size();
  while (p < end) {
    double v = 0;
    auto [next, ec] = std::from_chars(p, end, v);
    if (ec != std::errc() || !std::isfinite(v)) {
      throw std::invalid_argument(what + " '" + text + "': not a finite number");
    }
    out.push_back(v);
    p = next;
    if (p < end && *p == separator && p + 1 < end) {
      ++p;
    } else if (p < end) {
      throw std::invalid_argument(what + " '" + text + "': unexpected '" + std::string(1, *p) + "'");
    }
  }
  if (out.empty()) throw std::invalid_argument(what + " is empty");
  return out;
}

Eigen::Vector3d ParseDirection(const std::string& text, const std::string& what) {
  const std::vector<double> v = ParseNumbers(text, ',', what);
  if (v.size() != 3) throw std::invalid_argument(what + " '" + text + "': expected x,y,z");
  const Eigen::Vector3d d(v[0], v[1], v[2]);
  if (!(d.norm() > 0) || !d.allFinite()) throw std::invalid_argument(what + " '" + text + "': not a direction");
  return d;
}

}  // namespace candi::app

#include "core/text_format.h"

#include <charconv>
#include <cmath>
#include <locale>
#include <sstream>
#include <stdexcept>

namespace candi {

// Fixed notation for ordinary magnitudes (survey coordinates read as 500000.123, never 5e+05),
// scientific only where fixed would be long. Both are the shortest text that round-trips.
char* AppendDouble(char* buf, double value) {
  const double a = std::fabs(value);
  const bool fixed = a == 0.0 || (a >= 1e-4 && a < 1e16);
  return fixed ? std::to_chars(buf, buf + 48, value, std::chars_format::fixed).ptr
               : std::to_chars(buf, buf + 48, value).ptr;
}

char* AppendFloat(char* buf, float value) {
  const float a = std::fabs(value);
  const bool fixed = a == 0.0f || (a >= 1e-4f && a < 1e7f);
  return fixed ? std::to_chars(buf, buf + 48, value, std::chars_format::fixed).ptr
               : std::to_chars(buf, buf + 48, value).ptr;
}

std::string FormatDouble(double value) {
  char buf[48];
  return std::string(buf, AppendDouble(buf, value));
}

std::string FormatFloat(float value) {
  char buf[48];
  return std::string(buf, AppendFloat(buf, value));
}

std::string FormatSignificant(double value, int digits) {
  std::ostringstream text;
  text.imbue(std::locale::classic());
  text.precision(digits);
  text << value;
  return text.str();
}

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

}  // namespace candi

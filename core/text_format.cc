#include "core/text_format.h"

#include <charconv>

namespace candi {

char* AppendDouble(char* buf, double value) { return std::to_chars(buf, buf + 32, value).ptr; }
char* AppendFloat(char* buf, float value) { return std::to_chars(buf, buf + 32, value).ptr; }

std::string FormatDouble(double value) {
  char buf[32];
  return std::string(buf, AppendDouble(buf, value));
}

std::string FormatFloat(float value) {
  char buf[32];
  return std::string(buf, AppendFloat(buf, value));
}

}  // namespace candi

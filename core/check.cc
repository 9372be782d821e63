#include "core/check.h"

namespace candi {

namespace {
std::string Compose(const std::string& path, const std::string& position,
                    const std::string& message) {
  std::string text = path;
  if (!position.empty()) text += ": " + position;
  return text + ": " + message;
}
}  // namespace

InputError::InputError(const std::string& path, const std::string& position,
                       const std::string& message)
    : std::runtime_error(Compose(path, position, message)), path_(path) {}

namespace internal {
void ThrowCheckFailure(const char* file, int line, const char* condition,
                       const std::string& message) {
  std::string text = std::string(file) + ":" + std::to_string(line) + ": check failed: " + condition;
  if (!message.empty()) text += ": " + message;
  throw InternalError(text);
}
}  // namespace internal

}  // namespace candi

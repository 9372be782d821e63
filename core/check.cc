#include "core/check.h"

#include <cxxabi.h>

#include <cstdlib>
#include <memory>

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

std::string OptionsStructName(const std::type_info& type) {
  int status = 0;
  const std::unique_ptr<char, void (*)(void*)> demangled(
      abi::__cxa_demangle(type.name(), nullptr, nullptr, &status), std::free);
  const std::string name = status == 0 && demangled ? demangled.get() : type.name();
  // Cut the namespaces: the text after the last "::" outside template arguments.
  size_t start = 0;
  int depth = 0;
  for (size_t i = 0; i + 1 < name.size(); ++i) {
    if (name[i] == '<') ++depth;
    if (name[i] == '>') --depth;
    if (depth == 0 && name[i] == ':' && name[i + 1] == ':') start = i + 2;
  }
  return name.substr(start);
}

void ThrowOptionError(const std::type_info& type, const std::string& field_text,
                      const std::string& message) {
  throw std::invalid_argument(OptionsStructName(type) + "::" + field_text + "; " + message);
}
}  // namespace internal

}  // namespace candi

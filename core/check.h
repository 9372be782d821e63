// Failure reporting for candi.
//
// Three kinds of failure, three mechanisms (STYLE.md rule 4):
//  - misuse of an API (a violated precondition): CANDI_CHECK throws InternalError with file:line;
//  - a bad input file or a failed external process: InputError naming the path and the position
//    (line, byte, record) or exit code;
//  - an algorithm that did not converge: a Summary with a message, never an exception.
// The `candi` command maps InputError to exit code 2 and InternalError to exit code 3.
// Invalid options (STYLE.md rule 3) throw std::invalid_argument from FooOptions::Check(), written
// with the CANDI_CHECK_OPTION_* macros at the end of this file.
#pragma once

#include <cstddef>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <typeinfo>

#include "core/text_format.h"

namespace candi {

// A bad input: a file that cannot be read or parsed, a value out of range in a file, a failed
// external process. what() reads "<path>: <position>: <message>" when position is known.
class InputError : public std::runtime_error {
 public:
  InputError(const std::string& path, const std::string& position, const std::string& message);
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// A violated precondition or invariant inside candi (a bug or API misuse).
class InternalError : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

namespace internal {
[[noreturn]] void ThrowCheckFailure(const char* file, int line, const char* condition,
                                    const std::string& message);
}  // namespace internal

}  // namespace candi

// CANDI_CHECK(cond) << "message";  Throws candi::InternalError("file:line: check failed: cond:
// message") when cond is false. The streamed message is only built on failure.
#define CANDI_CHECK(condition)                                                             \
  if (condition) {                                                                         \
  } else                                                                                   \
    ::candi::internal::CheckMessage(__FILE__, __LINE__, #condition)

#define CANDI_CHECK_EQ(a, b) CANDI_CHECK((a) == (b)) << #a " = " << (a) << ", " #b " = " << (b) << " "
#define CANDI_CHECK_LT(a, b) CANDI_CHECK((a) < (b)) << #a " = " << (a) << ", " #b " = " << (b) << " "
#define CANDI_CHECK_LE(a, b) CANDI_CHECK((a) <= (b)) << #a " = " << (a) << ", " #b " = " << (b) << " "

namespace candi::internal {
// Collects a streamed message and throws when destroyed (at the end of the CANDI_CHECK statement).
class CheckMessage {
 public:
  CheckMessage(const char* file, int line, const char* condition)
      : file_(file), line_(line), condition_(condition) {}
  CheckMessage(const CheckMessage&) = delete;
  CheckMessage& operator=(const CheckMessage&) = delete;
  [[noreturn]] ~CheckMessage() noexcept(false) {
    ThrowCheckFailure(file_, line_, condition_, stream_.str());
  }
  template <typename T>
  CheckMessage& operator<<(const T& value) {
    stream_ << value;
    return *this;
  }

 private:
  const char* file_;
  int line_;
  const char* condition_;
  std::ostringstream stream_;
};
}  // namespace candi::internal

// Options checks, one line per rule inside `void FooOptions::Check() const` (as COLMAP's
// CHECK_OPTION_*). A rule that fails throws std::invalid_argument("FooOptions::field = value;
// must be RULE"): FooOptions is the type of *this without its namespaces, field the macro
// argument as written (a nested field reads "tiles.tile"), value as OptionValueText prints it.
// Bounds print as written (write literals or field names). Every comparison fails on NaN. The
// rule text of CANDI_CHECK_OPTION, _MSG and _PAIR may be a std::string; it is only built when the
// check fails.
//
//   CANDI_CHECK_OPTION_GT(spacing, 0);          // "FooOptions::spacing = -1; must be > 0"
//   CANDI_CHECK_OPTION_GE / _LT / _LE            // ">= 0", "< 1", "<= 1"
//   CANDI_CHECK_OPTION_IN(alpha, 0, 1);         // "FooOptions::alpha = 1.5; must be in [0, 1]"
//   CANDI_CHECK_OPTION_EACH_IN(shares, 0, 16);  // "FooOptions::shares[2] = 17; must be in [0, 16]"
//   CANDI_CHECK_OPTION(r >= 0 && std::isfinite(r), r, "finite and >= 0");
//                                      // "FooOptions::r = inf; must be finite and >= 0"
//   CANDI_CHECK_OPTION_MSG(!name.empty(), name, "must name a file");
//                                      // "FooOptions::name = ; must name a file"
//   CANDI_CHECK_OPTION_PAIR((a > 0) != (b > 0), a, b, "exactly one must be > 0");
//                                      // "FooOptions::a = 0 and b = 0; exactly one must be > 0"
#define CANDI_CHECK_OPTION_MSG(condition, field, message)                                 \
  do {                                                                                    \
    if (!(condition)) {                                                                   \
      ::candi::internal::ThrowOptionError(                                                \
          typeid(*this), ::candi::internal::OptionFieldText(#field, (field)), (message)); \
    }                                                                                     \
  } while (false)

#define CANDI_CHECK_OPTION(condition, field, rule) \
  CANDI_CHECK_OPTION_MSG(condition, field, ::std::string("must be ") + (rule))

#define CANDI_CHECK_OPTION_PAIR(condition, field1, field2, message)         \
  do {                                                                      \
    if (!(condition)) {                                                     \
      ::candi::internal::ThrowOptionError(                                  \
          typeid(*this),                                                    \
          ::candi::internal::OptionFieldText(#field1, (field1)) + " and " + \
              ::candi::internal::OptionFieldText(#field2, (field2)),        \
          (message));                                                       \
    }                                                                       \
  } while (false)

#define CANDI_CHECK_OPTION_GT(field, bound) \
  CANDI_CHECK_OPTION((field) > (bound), field, "> " #bound)
#define CANDI_CHECK_OPTION_GE(field, bound) \
  CANDI_CHECK_OPTION((field) >= (bound), field, ">= " #bound)
#define CANDI_CHECK_OPTION_LT(field, bound) \
  CANDI_CHECK_OPTION((field) < (bound), field, "< " #bound)
#define CANDI_CHECK_OPTION_LE(field, bound) \
  CANDI_CHECK_OPTION((field) <= (bound), field, "<= " #bound)
#define CANDI_CHECK_OPTION_IN(field, low, high) \
  CANDI_CHECK_OPTION((field) >= (low) && (field) <= (high), field, "in [" #low ", " #high "]")

// Each element of a sequence (std::vector, an Eigen vector) in [low, high], named by its index.
#define CANDI_CHECK_OPTION_EACH_IN(field, low, high)                                            \
  do {                                                                                          \
    size_t candi_option_index_ = 0;                                                             \
    for (const auto& candi_option_value_ : (field)) {                                           \
      if (!(candi_option_value_ >= (low) && candi_option_value_ <= (high))) {                   \
        ::candi::internal::ThrowOptionError(                                                    \
            typeid(*this),                                                                      \
            ::candi::internal::OptionFieldText(                                                 \
                #field "[" + ::std::to_string(candi_option_index_) + "]", candi_option_value_), \
            "must be in [" #low ", " #high "]");                                                \
      }                                                                                         \
      ++candi_option_index_;                                                                    \
    }                                                                                           \
  } while (false)

namespace candi::internal {

// "OpacityOptions" for candi::sampling::OpacityOptions: the demangled name without its
// qualifiers (namespaces, enclosing classes).
std::string OptionsStructName(const std::type_info& type);

// Throws std::invalid_argument("<struct>::<field_text>; <message>").
[[noreturn]] void ThrowOptionError(const std::type_info& type, const std::string& field_text,
                                   const std::string& message);

template <typename T>
struct IsOptional : std::false_type {};
template <typename T>
struct IsOptional<std::optional<T>> : std::true_type {};

// An option's value as text: integers in full, floating point as the shortest text that reads
// back the same (FormatDouble, FormatFloat), bools as true/false, strings as they are, enums as
// their number, an optional as its value (or "none"), a sequence as "(a, b, c)".
template <typename T>
std::string OptionValueText(const T& value) {
  if constexpr (std::is_same_v<T, bool>) {
    return value ? "true" : "false";
  } else if constexpr (std::is_same_v<T, float>) {
    return FormatFloat(value);
  } else if constexpr (std::is_floating_point_v<T>) {
    return FormatDouble(static_cast<double>(value));
  } else if constexpr (std::is_integral_v<T> && std::is_signed_v<T>) {
    return std::to_string(static_cast<long long>(value));
  } else if constexpr (std::is_integral_v<T>) {
    return std::to_string(static_cast<unsigned long long>(value));
  } else if constexpr (std::is_enum_v<T>) {
    return OptionValueText(static_cast<std::underlying_type_t<T>>(value));
  } else if constexpr (std::is_convertible_v<const T&, std::string_view>) {
    return std::string(std::string_view(value));
  } else if constexpr (IsOptional<T>::value) {
    return value ? OptionValueText(*value) : std::string("none");
  } else {
    std::string text = "(";
    const char* separator = "";
    for (const auto& element : value) {
      text += separator + OptionValueText(element);
      separator = ", ";
    }
    return text + ")";
  }
}

// "field = value".
template <typename T>
std::string OptionFieldText(const std::string& field, const T& value) {
  return field + " = " + OptionValueText(value);
}

}  // namespace candi::internal

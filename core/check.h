// Failure reporting for candi.
//
// Three kinds of failure, three mechanisms (STYLE.md rule 4):
//  - misuse of an API (a violated precondition): CANDI_CHECK throws InternalError with file:line;
//  - a bad input file or a failed external process: InputError naming the path and the position
//    (line, byte, record) or exit code;
//  - an algorithm that did not converge: a Summary with a message, never an exception.
// The `candi` command maps InputError to exit code 2 and InternalError to exit code 3.
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

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

#include "apps/failure.h"

#include <new>

#include "apps/cli.h"
#include "core/check.h"

namespace candi::apps {

FailureReport DescribeFailure(std::exception_ptr failure) {
  try {
    std::rethrow_exception(failure);
  } catch (const InputError& e) {
    return {kBadInput, std::string("candi: error: ") + e.what()};
  } catch (const std::invalid_argument& e) {
    return {kUsage, std::string("candi: invalid option value: ") + e.what()};
  } catch (const InternalError& e) {
    return {kInternal, std::string("candi: internal error (please report): ") + e.what()};
  } catch (const std::bad_alloc&) {
    return {kInternal, "candi: internal error: out of memory"};
  } catch (const std::exception& e) {
    return {kInternal, std::string("candi: internal error: ") + e.what()};
  } catch (...) {
    return {kInternal, "candi: internal error: an unknown exception"};
  }
}

std::pair<int, std::string> DescribeFailureForMpi(std::exception_ptr failure) {
  const FailureReport report = DescribeFailure(failure);
  return {report.exit_code, report.text};
}

}  // namespace candi::apps

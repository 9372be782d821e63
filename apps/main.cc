// candi: the command line. Parses (cli.cc), runs a subcommand, maps failures to exit codes:
// 0 ok, 1 usage (bad option or value), 2 bad input (file, data, external process), 3 internal.
#include <cstdio>
#include <new>
#include <stdexcept>

#include "apps/commands.h"
#include "core/check.h"

namespace candi::app {
int RunCli(int argc, char** argv);
}

int main(int argc, char** argv) {
  using namespace candi::app;
  try {
    return RunCli(argc, argv);
  } catch (const candi::InputError& e) {
    std::fprintf(stderr, "candi: error: %s\n", e.what());
    return kBadInput;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "candi: invalid option value: %s\n", e.what());
    return kUsage;
  } catch (const candi::InternalError& e) {
    std::fprintf(stderr, "candi: internal error (please report): %s\n", e.what());
    return kInternal;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "candi: internal error: out of memory\n");
    return kInternal;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "candi: internal error: %s\n", e.what());
    return kInternal;
  }
}

// candi: the command line. Parses (cli.cc), runs a subcommand, maps failures to exit codes:
// 0 ok, 1 usage (bad option or value), 2 bad input (file, data, external process), 3 internal.
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>
#include <stdexcept>
#include <string>

#include "apps/commands.h"
#include "core/check.h"

namespace candi::app {
int RunCli(int argc, char** argv);
}

#if !CANDI_WITH_RELIEF
namespace {

// True for `candi [global flags] relief ...` and `candi [flags] bench ... relief ...`.
bool WantsRelief(int argc, char** argv) {
  int i = 1;
  while (i < argc && argv[i][0] == '-') ++i;
  if (i >= argc) return false;
  if (!std::strcmp(argv[i], "relief")) return true;
  if (std::strcmp(argv[i], "bench") != 0) return false;
  for (++i; i < argc; ++i) {
    if (!std::strcmp(argv[i], "relief")) return true;
  }
  return false;
}

// Replaces this process with candi-relief from this executable's folder (same arguments).
int ExecRelief(char** argv) {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  std::string path = "candi-relief";
  if (n > 0) {
    self[n] = '\0';
    const std::string exe(self);
    path = exe.substr(0, exe.rfind('/') + 1) + "candi-relief";
  }
  execv(path.c_str(), argv);
  std::fprintf(stderr, "candi: internal error: the relief commands are run by %s, which could not be started: %s\n",
               path.c_str(), std::strerror(errno));
  return candi::app::kInternal;
}

}  // namespace
#endif

int main(int argc, char** argv) {
  using namespace candi::app;
#if !CANDI_WITH_RELIEF
  if (WantsRelief(argc, argv)) return ExecRelief(argv);
#endif
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

// candi: the command line. Parses (cli.cc), runs a subcommand, maps failures to exit codes:
// 0 ok, 1 usage (bad option or value), 2 bad input (file, data, external process), 3 internal.
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>
#include <stdexcept>
#include <string>

#include "apps/cli.h"
#include "apps/failure.h"
#include "core/check.h"
#include "core/interrupt.h"
#include "core/mapped_file.h"


namespace {

// The commands are split over three executables from the same sources, so that a call loads only
// the shared libraries it needs (dynamic linking is most of a short call's time):
//   candi        everything else (start-up ~0.1 s);
//   candi-pcl    register, register-scans and clean (PCL: its BIND_NOW libraries cost ~0.4 s to load);
//   candi-relief the relief commands and the demo, and everything else too (libtorch: seconds
//                to load).
// cli.cc is the same in all three (every command's options and --help); an executable without a
// command's code hands the call over, before parsing, to the sibling that has it (same folder,
// same arguments).
enum Group { kCore, kPcl, kRelief };

// True for `-h` or `--help` among the arguments (before a `--`).
bool AsksForHelp(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--")) return false;
    if (!std::strcmp(argv[i], "-h") || !std::strcmp(argv[i], "--help")) return true;
  }
  return false;
}

// The group of `candi [global flags] COMMAND ...`; `bench ... relief` is a relief command. Help is
// answered here, whatever the command: cli.cc is the same in every executable, and so is the text,
// without the seconds libtorch takes to load (or the sibling, when it is not built).
Group CommandGroup(int argc, char** argv) {
  if (AsksForHelp(argc, argv)) return kCore;
  int i = 1;
  while (i < argc && argv[i][0] == '-') ++i;
  if (i >= argc) return kCore;
  const char* command = argv[i];
  if (!std::strcmp(command, "relief")) {
    // `relief place` (Ceres, no libtorch) runs here; the other relief commands need the network.
    return i + 1 < argc && !std::strcmp(argv[i + 1], "place") ? kCore : kRelief;
  }
  if (!std::strcmp(command, "register") || !std::strcmp(command, "register-scans") ||
      !std::strcmp(command, "clean")) {
    return kPcl;
  }
  // The demo predicts its relief panels' depth: in candi-relief, so libtorch loads once.
  if (!std::strcmp(command, "demo")) return kRelief;
  if (!std::strcmp(command, "bench")) {
    for (++i; i < argc; ++i)
      if (!std::strcmp(argv[i], "relief")) return kRelief;
  }
  return kCore;
}

bool HasGroup(Group group) {
  switch (group) {
    case kCore: return true;
    case kPcl: return CANDI_WITH_PCL;
    case kRelief: return CANDI_WITH_RELIEF;
  }
  return false;
}

// Replaces this process with `name` from this executable's folder (same arguments).
int Exec(const char* name, char** argv) {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  std::string path = name;
  if (n > 0) {
    self[n] = '\0';
    const std::string exe(self);
    path = exe.substr(0, exe.rfind('/') + 1) + name;
  }
  execv(path.c_str(), argv);
  std::fprintf(stderr, "candi: internal error: this command is run by %s, which could not be started: %s\n",
               path.c_str(), std::strerror(errno));
  return candi::apps::kInternal;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace candi::apps;
  const Group group = CommandGroup(argc, argv);
  if (!HasGroup(group)) return Exec(group == kPcl ? "candi-pcl" : "candi-relief", argv);
  // Before any thread starts: an interrupt removes unfinished outputs and stops child processes.
  candi::InstallInterruptHandler("candi");
  // A mapped input cut short, or failing on disk, while it is read: an error, not a crash.
  candi::InstallMappedFileFaultHandler();
  try {
    return RunCli(argc, argv);
  } catch (const ReportedFailure& e) {
    return e.exit_code();
  } catch (...) {
    const FailureReport report = DescribeFailure(std::current_exception());
    std::fprintf(stderr, "%s\n", report.text.c_str());
    return report.exit_code;
  }
}

#include "core/interrupt.h"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <initializer_list>
#include <map>
#include <mutex>
#include <thread>

namespace candi {

namespace {

struct Registry {
  std::mutex mutex;
  int next_id = 0;
  std::map<int, std::string> temps;
  std::map<int, pid_t> children;
  std::string program = "candi";
  bool installed = false;
};

Registry& Reg() {
  static Registry* registry = new Registry();  // never destroyed: the watcher may outlive main
  return *registry;
}

sigset_t Signals() {
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGHUP);
  return set;
}

const char* SignalName(int sig) {
  switch (sig) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    case SIGHUP: return "SIGHUP";
  }
  return "a signal";
}

[[noreturn]] void Watch(sigset_t set) {
  int sig = 0;
  while (sigwait(&set, &sig) != 0) {
  }
  Registry& r = Reg();
  r.mutex.lock();  // kept: nothing commits from here on
  for (const auto& [id, pid] : r.children) kill(pid, SIGTERM);
  size_t removed = 0;
  for (const auto& [id, path] : r.temps) {
    std::error_code ec;
    if (std::filesystem::remove_all(path, ec) > 0) ++removed;
  }
  std::fprintf(stderr, "\n%s: interrupted by %s; %sfiles finished before it are complete and kept "
                       "(candi build --resume continues a build)\n",
               r.program.c_str(), SignalName(sig),
               removed > 0 ? "unfinished output removed; " : "");
  std::fflush(stderr);
  // End the process by the same signal, so the parent sees what happened.
  signal(sig, SIG_DFL);
  sigset_t one;
  sigemptyset(&one);
  sigaddset(&one, sig);
  pthread_sigmask(SIG_UNBLOCK, &one, nullptr);
  raise(sig);
  _exit(128 + sig);
}

}  // namespace

void InstallInterruptHandler(const char* program) {
  Registry& r = Reg();
  {
    std::lock_guard<std::mutex> lock(r.mutex);
    if (r.installed) return;
    r.installed = true;
    r.program = program;
  }
  sigset_t set = Signals();
  // A signal the parent left ignored (nohup, background jobs of a non-interactive shell) stays so.
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction old;
    if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) sigdelset(&set, sig);
  }
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
  std::thread(Watch, set).detach();
}

void ChildSignalMask(sigset_t* mask) { sigemptyset(mask); }

int RegisterTempPath(const std::string& path) {
  Registry& r = Reg();
  std::lock_guard<std::mutex> lock(r.mutex);
  const int id = r.next_id++;
  r.temps[id] = path;
  return id;
}

int CreateTempDirectory(const std::string& path, std::error_code* ec) {
  Registry& r = Reg();
  std::lock_guard<std::mutex> lock(r.mutex);
  ec->clear();
  std::filesystem::create_directories(path, *ec);
  if (*ec) return -1;
  const int id = r.next_id++;
  r.temps[id] = path;
  return id;
}

int MakeTempDirectory(std::string* pattern) {
  Registry& r = Reg();
  std::lock_guard<std::mutex> lock(r.mutex);
  if (mkdtemp(pattern->data()) == nullptr) return -1;
  const int id = r.next_id++;
  r.temps[id] = *pattern;
  return id;
}

void UnregisterTempPath(int id) {
  Registry& r = Reg();
  std::lock_guard<std::mutex> lock(r.mutex);
  r.temps.erase(id);
}

TempFolder::~TempFolder() { Reset("", -1); }

void TempFolder::Reset(std::string path, int id) {
  if (!path_.empty()) {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  if (id_ >= 0) UnregisterTempPath(id_);
  path_ = std::move(path);
  id_ = id;
}

int RegisterChild(pid_t pid) {
  Registry& r = Reg();
  std::lock_guard<std::mutex> lock(r.mutex);
  const int id = r.next_id++;
  r.children[id] = pid;
  return id;
}

void UnregisterChild(int id) {
  Registry& r = Reg();
  std::lock_guard<std::mutex> lock(r.mutex);
  r.children.erase(id);
}

void CommitTempPath(int id, const std::function<void()>& step) {
  Registry& r = Reg();
  std::lock_guard<std::mutex> lock(r.mutex);
  struct Erase {
    Registry& r;
    int id;
    ~Erase() { r.temps.erase(id); }
  } erase{r, id};
  step();
}

}  // namespace candi

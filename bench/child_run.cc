#include "bench/child_run.h"

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>

#include "core/check.h"
#include "core/interrupt.h"

namespace candi::bench {

// Runs argv (PATH lookup), capturing stdout; stderr passes through.
ChildRun RunChild(const std::vector<std::string>& argv) {
  int pipe_fd[2];
  CANDI_CHECK(pipe(pipe_fd) == 0) << "pipe";
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  CANDI_CHECK(pid >= 0) << "fork";
  if (pid == 0) {
    sigset_t mask;  // candi's interrupt handler blocks these signals; the child handles its own
    ChildSignalMask(&mask);
    sigprocmask(SIG_SETMASK, &mask, nullptr);
    dup2(pipe_fd[1], 1);
    close(pipe_fd[0]);
    close(pipe_fd[1]);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execvp(args[0], args.data());
    std::fprintf(stderr, "cannot run %s: %s\n", args[0], std::strerror(errno));
    _exit(127);
  }
  close(pipe_fd[1]);
  const int registered = RegisterChild(pid);  // stopped if candi is interrupted
  ChildRun r;
  char buffer[4096];
  ssize_t n;
  while ((n = read(pipe_fd[0], buffer, sizeof(buffer))) > 0) r.out.append(buffer, static_cast<size_t>(n));
  close(pipe_fd[0]);
  int status = 0;
  struct rusage usage {};
  wait4(pid, &status, 0, &usage);
  UnregisterChild(registered);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.peak_mb = usage.ru_maxrss / 1024.0;
  r.cpu_seconds = usage.ru_utime.tv_sec + usage.ru_stime.tv_sec + 1e-6 * (usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
  return r;
}

std::string SelfPath() {
  char self[4096];
  const ssize_t n = readlink("/proc/self/exe", self, sizeof(self) - 1);
  CANDI_CHECK(n > 0) << "/proc/self/exe";
  self[n] = '\0';
  return self;
}

}  // namespace candi::bench

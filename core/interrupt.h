// Interrupts (SIGINT, SIGTERM, SIGHUP) of a long command: nothing half-written stays behind.
//
// InstallInterruptHandler() blocks these signals in the calling thread (and so in every thread
// created after it) and waits for them on a thread of its own. When one arrives, that thread
// takes the registry lock (so a commit in progress completes first), sends SIGTERM to the
// registered child processes (COLMAP, candi-relief), removes every registered temporary file or
// folder (an AtomicFile's, a pack's build folder), says so on stderr, and ends the process by the
// same signal (exit status 128 + signal in a shell). Files already committed (renamed into place)
// are complete and kept, so a command that can resume (`candi build --resume`) continues from
// them. Without the handler (library use, tests), registration costs a lock and does nothing else.
#pragma once

#include <sys/types.h>

#include <functional>
#include <string>
#include <system_error>
#include <utility>

namespace candi {

// Installs the handler (idempotent); call first thing in main(), before threads start. `program`
// names the process in the message. Child processes must be started with the signals unblocked
// (ChildSignalMask).
void InstallInterruptHandler(const char* program);

// The signal mask a child process should start with (empty: the handler's block is not inherited).
void ChildSignalMask(sigset_t* mask);

// A temporary file or folder to remove on interrupt; returns an id for UnregisterTempPath.
int RegisterTempPath(const std::string& path);
// Creates the folder `path` (with its parents; it may exist) and registers it, in one step the
// interrupt waits for: an interrupt comes either before (nothing is created, as a thread that
// creates folders while the handler removes them could do) or after (the folder is removed).
// Returns the id, or -1 with *ec set when the folder cannot be created.
int CreateTempDirectory(const std::string& path, std::error_code* ec);
// mkdtemp(*pattern) (ending in XXXXXX, which becomes the folder's name) in that step; -1 (errno
// set) when it fails.
int MakeTempDirectory(std::string* pattern);
void UnregisterTempPath(int id);

// A child process to stop on interrupt; returns an id for UnregisterChild.
int RegisterChild(pid_t pid);
void UnregisterChild(int id);

// Runs `step` (the rename of temporary `id` into place) with the interrupt held off, then
// unregisters `id` (also when `step` throws): the handler sees either the temporary or the
// finished file, never half of the step.
void CommitTempPath(int id, const std::function<void()>& step);

// A registered temporary folder (CreateTempDirectory, MakeTempDirectory, RegisterTempPath) that
// is removed, with everything in it, and unregistered when this is destroyed: at the end, by an
// exception, or (registered) by an interrupt. Keep() after the folder was renamed into place.
class TempFolder {
 public:
  TempFolder() = default;
  TempFolder(std::string path, int id) : path_(std::move(path)), id_(id) {}
  ~TempFolder();
  TempFolder(const TempFolder&) = delete;
  TempFolder& operator=(const TempFolder&) = delete;
  // Takes `path` and `id` (the folder held before, if any, is removed first).
  void Reset(std::string path, int id);
  const std::string& path() const { return path_; }
  int id() const { return id_; }
  // Not removed when this is destroyed (only unregistered).
  void Keep() { path_.clear(); }

 private:
  std::string path_;
  int id_ = -1;
};

}  // namespace candi

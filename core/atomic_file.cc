#include "core/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <vector>

#include "core/check.h"
#include "core/interrupt.h"
#include "core/log.h"

namespace candi {

AtomicFile::AtomicFile(const std::string& path) : path_(path) {
  if (path.empty()) throw InputError("output path is empty");
  struct stat st;
  if (stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode)) {
    throw InputError(path, "", "is a directory, not an output file");
  }
  std::vector<char> pattern(path.begin(), path.end());
  const std::string suffix = ".candi-tmp-XXXXXX";
  pattern.insert(pattern.end(), suffix.begin(), suffix.end());
  pattern.push_back('\0');
  const int fd = mkstemp(pattern.data());
  if (fd < 0) {
    const int err = errno;
    throw InputError(path, "", std::string("cannot create output: ") + std::strerror(err));
  }
  temp_path_ = pattern.data();
  interrupt_id_ = RegisterTempPath(temp_path_);
  // mkstemp creates 0600; give the file the usual permissions (respecting umask).
  const mode_t mask = umask(0);
  umask(mask);
  fchmod(fd, 0666 & ~mask);
  file_ = fdopen(fd, "w+b");
  if (file_ == nullptr) {
    const int err = errno;
    close(fd);
    unlink(temp_path_.c_str());
    throw InputError(path, "", std::string("cannot open output: ") + std::strerror(err));
  }
  setvbuf(file_, nullptr, _IOFBF, 1 << 20);
}

AtomicFile::~AtomicFile() {
  if (!committed_) Discard();
}

void AtomicFile::Discard() {
  if (file_ != nullptr) {
    std::fclose(file_);
    file_ = nullptr;
  }
  if (!temp_path_.empty()) unlink(temp_path_.c_str());
  UnregisterTempPath(interrupt_id_);
  interrupt_id_ = -1;
}

void AtomicFile::Fail(const std::string& what, int err) {
  Discard();
  committed_ = true;  // nothing left to clean up
  throw InputError(path_, "", what + ": " + std::strerror(err) + " (the destination is unchanged)");
}

void AtomicFile::Write(const void* data, size_t size) {
  CANDI_CHECK(file_ != nullptr) << "AtomicFile::Write after Commit or failure";
  if (size == 0) return;
  if (std::fwrite(data, 1, size, file_) != size) Fail("write failed", errno);
  written_ += size;
  // For tests (tests/fault_test.cc): CANDI_TEST_INTERRUPT_AT_BYTE=<n> interrupts the process, as
  // a user's Ctrl-C would, once a file being written holds n bytes: mid-write, at a point that no
  // timing decides. The interrupt handler's thread ends the process; this one waits for it.
  static const uint64_t interrupt_at = [] {
    const char* text = std::getenv("CANDI_TEST_INTERRUPT_AT_BYTE");
    return text != nullptr ? std::strtoull(text, nullptr, 10) : uint64_t{0};
  }();
  if (interrupt_at > 0 && written_ >= interrupt_at) {
    kill(getpid(), SIGINT);
    for (;;) pause();
  }
}

void AtomicFile::Reserve(uint64_t bytes) {
  CANDI_CHECK(file_ != nullptr) << "AtomicFile::Reserve after Commit or failure";
  if (bytes == 0) return;
  // FALLOC_FL_KEEP_SIZE: blocks are allocated, the size still grows only as data is written.
  if (fallocate(fileno(file_), FALLOC_FL_KEEP_SIZE, 0, static_cast<off_t>(bytes)) != 0) {
    if (errno == ENOSPC || errno == EFBIG) Fail("cannot reserve " + std::to_string(bytes) + " bytes", errno);
  }
}

void AtomicFile::WriteAt(uint64_t offset, const void* data, size_t size) {
  CANDI_CHECK(file_ != nullptr) << "AtomicFile::WriteAt after Commit or failure";
  CANDI_CHECK(offset + size <= written_) << "WriteAt beyond the written part";
  if (std::fflush(file_) != 0) Fail("write failed", errno);
  const ssize_t n = pwrite(fileno(file_), data, size, static_cast<off_t>(offset));
  if (n != static_cast<ssize_t>(size)) Fail("write failed", n < 0 ? errno : ENOSPC);
}

void AtomicFile::Commit() {
  CANDI_CHECK(file_ != nullptr) << "AtomicFile::Commit twice";
  if (std::fflush(file_) != 0) Fail("write failed", errno);
  if (std::ferror(file_)) Fail("write failed", EIO);
  FILE* f = file_;
  file_ = nullptr;
  if (std::fclose(f) != 0) {
    const int err = errno;
    unlink(temp_path_.c_str());
    UnregisterTempPath(interrupt_id_);
    committed_ = true;
    throw InputError(path_, "", std::string("close failed: ") + std::strerror(err) +
                                    " (the destination is unchanged)");
  }
  committed_ = true;
  CommitTempPath(interrupt_id_, [this] {
    if (std::rename(temp_path_.c_str(), path_.c_str()) != 0) {
      const int err = errno;
      unlink(temp_path_.c_str());
      throw InputError(path_, "", std::string("cannot rename into place: ") + std::strerror(err));
    }
  });
}

void WriteFileAtomic(const std::string& path, const std::string& contents) {
  AtomicFile file(path);
  file.Write(contents);
  file.Commit();
}

std::string ReadFileToString(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", std::string("cannot open: ") + std::strerror(errno));
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw InputError(path, "", "read error");
  return ss.str();
}

void CheckOutputFolder(const std::string& output) {
  std::filesystem::path folder = std::filesystem::path(output).parent_path();
  if (folder.empty()) folder = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(folder, ec)) {
    throw InputError(output, "", "output folder '" + folder.string() + "' " +
                                     (std::filesystem::exists(folder, ec) ? "is not a folder" : "does not exist"));
  }
  if (::access(folder.c_str(), W_OK) != 0) {
    throw InputError(output, "", "output folder '" + folder.string() + "' is not writable");
  }
}

void CheckReplaceableFolder(const std::string& output, bool (*replaceable)(const std::string&),
                            const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_symlink(output, ec)) {
    throw InputError(output, "",
                     "is a symbolic link (to " + fs::read_symlink(output, ec).string() +
                         "); give the folder itself, not a link to it");
  }
  if (fs::exists(output, ec) && !replaceable(output)) {
    throw InputError(output, "", "exists and is not " + what + "; not overwriting it");
  }
  CheckOutputFolder(output);
}

void ReplaceFolder(const std::string& temp, const std::string& output, bool (*replaceable)(const std::string&),
                   const std::string& what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::is_symlink(output, ec)) {
    throw InputError(output, "", "is a symbolic link; not replacing it (give the folder itself)");
  }
  if (fs::exists(output, ec)) {
    if (!replaceable(output)) throw InputError(output, "", "exists and is not " + what + "; not overwriting it");
    const std::string old = output + ".candi-old-" + std::to_string(getpid());
    fs::rename(output, old, ec);
    if (ec) throw InputError(output, "", "cannot move the old " + what + " aside: " + ec.message());
    fs::rename(temp, output, ec);
    if (ec) {
      std::error_code ignored;
      fs::rename(old, output, ignored);
      throw InputError(output, "", "cannot rename the new " + what + " into place: " + ec.message());
    }
    std::error_code removed, ignored;
    fs::remove_all(old, removed);
    if (removed || fs::exists(old, ignored)) {
      LogWarning(output + ": the new " + what +
                 " is in place, but the old one could not be removed: it is left as " + old + " (" +
                 (removed ? removed.message() : std::string("still there")) +
                 "); remove it by hand");
    }
    return;
  }
  fs::rename(temp, output, ec);
  if (ec) throw InputError(output, "", "cannot rename the new " + what + " into place: " + ec.message());
}

}  // namespace candi

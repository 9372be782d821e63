#include "core/mapped_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <signal.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstring>
#include <limits>
#include <mutex>
#include <utility>

#include "core/binary_file.h"
#include "core/check.h"

namespace candi {

namespace {

// The mapped files, for the SIGBUS handler: a fixed table read without locks (a slot is claimed
// by its `begin` going from 0 to the address; the path is written before `end` is published).
struct MappedRange {
  std::atomic<uintptr_t> begin{0}, end{0};
  char path[512];
};
constexpr int kMappedRanges = 64;
MappedRange g_ranges[kMappedRanges];

int RegisterRange(const uint8_t* data, uint64_t size, const std::string& path) {
  const uintptr_t begin = reinterpret_cast<uintptr_t>(data);
  for (int k = 0; k < kMappedRanges; ++k) {
    uintptr_t free = 0;
    if (!g_ranges[k].begin.compare_exchange_strong(free, begin)) continue;
    const size_t n = std::min(path.size(), sizeof(g_ranges[k].path) - 1);
    std::memcpy(g_ranges[k].path, path.data(), n);
    g_ranges[k].path[n] = '\0';
    g_ranges[k].end.store(begin + static_cast<uintptr_t>(size), std::memory_order_release);
    return k;
  }
  return -1;  // more files mapped at once than the table holds: their faults are not named
}

void UnregisterRange(int k) {
  if (k < 0) return;
  g_ranges[k].end.store(0, std::memory_order_release);
  g_ranges[k].begin.store(0, std::memory_order_release);
}

void WriteAll(const char* text, size_t n) {
  while (n > 0) {
    const ssize_t got = write(2, text, n);
    if (got <= 0) return;
    text += got;
    n -= static_cast<size_t>(got);
  }
}

// Async-signal-safe: names the file and byte of a fault inside a mapped file and exits with 2.
void OnBusError(int sig, siginfo_t* info, void*) {
  const uintptr_t at = reinterpret_cast<uintptr_t>(info->si_addr);
  for (const MappedRange& r : g_ranges) {
    const uintptr_t begin = r.begin.load(std::memory_order_acquire), end = r.end.load(std::memory_order_acquire);
    if (begin == 0 || end == 0 || at < begin || at >= end) continue;
    char digits[24];
    int n = 0;
    for (uintptr_t v = at - begin; n == 0 || v > 0; v /= 10) digits[n++] = static_cast<char>('0' + v % 10);
    char byte[24];
    for (int i = 0; i < n; ++i) byte[i] = digits[n - 1 - i];
    WriteAll(r.path, std::strlen(r.path));
    WriteAll(": byte ", 7);
    WriteAll(byte, static_cast<size_t>(n));
    static const char kWhat[] =
        ": the file was cut short or could not be read from the disk while it was read; the outputs "
        "are as they were\n";
    WriteAll(kWhat, sizeof(kWhat) - 1);
    _exit(2);
  }
  signal(sig, SIG_DFL);  // not a mapped file's: the default action (the fault repeats)
}

// A file's modification time in nanoseconds, part of what MapShared compares.
int64_t ModifiedNs(const struct stat& st) {
  return int64_t{st.st_mtim.tv_sec} * 1'000'000'000 + st.st_mtim.tv_nsec;
}

}  // namespace

void InstallMappedFileFaultHandler() {
  struct sigaction action;
  std::memset(&action, 0, sizeof(action));
  action.sa_sigaction = OnBusError;
  action.sa_flags = SA_SIGINFO;
  sigemptyset(&action.sa_mask);
  sigaction(SIGBUS, &action, nullptr);
}

MappedFile::MappedFile(const std::string& path) : path_(path) {
  bool regular = false;
  fd_ = OpenForReading(path, &size_, &regular);
  if (size_ > std::numeric_limits<size_t>::max() / 2) {
    close(fd_);
    throw InputError(
        path, "",
        "file of " + std::to_string(size_) + " bytes is larger than this machine can address");
  }
  void* p = regular && size_ > 0
                ? mmap(nullptr, static_cast<size_t>(size_), PROT_READ, MAP_PRIVATE, fd_, 0)
                : MAP_FAILED;
  if (p != MAP_FAILED) {
    data_ = static_cast<const uint8_t*>(p);
    mapped_ = true;
    struct stat st;
    if (fstat(fd_, &st) == 0) {
      device_ = static_cast<uint64_t>(st.st_dev);
      inode_ = static_cast<uint64_t>(st.st_ino);
      modified_ns_ = ModifiedNs(st);
    }
    range_ = RegisterRange(data_, size_, path_);
    madvise(p, static_cast<size_t>(size_), MADV_SEQUENTIAL);  // readers call WillNeed per range
  } else {
    try {
      ReadIntoMemory();
    } catch (...) {
      close(fd_);  // no destructor runs for a constructor that throws
      throw;
    }
  }
}

MappedFile::~MappedFile() {
  UnregisterRange(range_);
  if (mapped_) munmap(const_cast<uint8_t*>(data_), static_cast<size_t>(size_));
  if (fd_ >= 0) close(fd_);
}

// A pipe, a device or a filesystem that refuses mmap: read until the end, whatever stat said.
void MappedFile::ReadIntoMemory() {
  memory_.resize(static_cast<size_t>(size_));
  size_t used = 0;
  while (true) {
    if (used == memory_.size()) memory_.resize(std::max<size_t>(1 << 16, 2 * used));
    // In parts, so that a read error names a byte near where it happened.
    const size_t part = std::min<size_t>(memory_.size() - used, size_t{8} << 20);
    const ssize_t got = read(fd_, memory_.data() + used, part);
    if (got < 0 && errno == EINTR) continue;
    if (got < 0) {
      throw InputError(path_, "byte " + std::to_string(used),
                       std::string("read error: ") + std::strerror(errno));
    }
    if (got == 0) break;
    used += static_cast<size_t>(got);
  }
  memory_.resize(used);
  memory_.shrink_to_fit();
  data_ = memory_.data();
  size_ = used;
}

void MappedFile::CheckSize(uint64_t end, const std::string& what) const {
  if (!mapped_) return;
  struct stat st;
  if (fstat(fd_, &st) != 0 || static_cast<uint64_t>(st.st_size) >= end) return;
  throw InputError(path_, "byte " + std::to_string(st.st_size),
                   "the file shrank from " + std::to_string(size_) + " to " +
                       std::to_string(st.st_size) + " bytes while it was read (needed " +
                       std::to_string(end) + " bytes for " + what + ")");
}

std::shared_ptr<const MappedFile> MapShared(const std::string& path) {
  static std::mutex mutex;
  static std::vector<std::weak_ptr<const MappedFile>> live;
  struct stat st;
  const bool known = stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
  if (known) {
    const std::lock_guard<std::mutex> lock(mutex);
    for (const std::weak_ptr<const MappedFile>& w : live) {
      std::shared_ptr<const MappedFile> m = w.lock();
      if (m && m->mapped_ && m->path_ == path && m->device_ == static_cast<uint64_t>(st.st_dev) &&
          m->inode_ == static_cast<uint64_t>(st.st_ino) &&
          m->size_ == static_cast<uint64_t>(st.st_size) && m->modified_ns_ == ModifiedNs(st)) {
        return m;
      }
    }
  }
  // Mapped outside the lock (a read into memory can take long), then published.
  auto m = std::make_shared<const MappedFile>(path);
  if (m->mapped_) {
    const std::lock_guard<std::mutex> lock(mutex);
    live.erase(std::remove_if(live.begin(), live.end(), [](const auto& w) { return w.expired(); }),
               live.end());
    live.push_back(m);
  }
  return m;
}

void MappedFile::WillNeed(uint64_t offset, uint64_t n) const {
  if (!mapped_ || offset >= size_) return;
  const uint64_t page = static_cast<uint64_t>(sysconf(_SC_PAGESIZE));
  const uint64_t begin = offset / page * page;
  const uint64_t end = std::min(size_, offset + n);
  madvise(const_cast<uint8_t*>(data_) + begin, static_cast<size_t>(end - begin), MADV_WILLNEED);
}

}  // namespace candi

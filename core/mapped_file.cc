#include "core/mapped_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <limits>

#include "core/binary_file.h"
#include "core/check.h"

namespace candi {

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

void MappedFile::WillNeed(uint64_t offset, uint64_t n) const {
  if (!mapped_ || offset >= size_) return;
  const uint64_t page = static_cast<uint64_t>(sysconf(_SC_PAGESIZE));
  const uint64_t begin = offset / page * page;
  const uint64_t end = std::min(size_, offset + n);
  madvise(const_cast<uint8_t*>(data_) + begin, static_cast<size_t>(end - begin), MADV_WILLNEED);
}

}  // namespace candi

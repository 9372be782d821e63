#include "core/spill_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "core/check.h"

namespace candi {

SpillFile::~SpillFile() {
  if (fd_ >= 0) close(fd_);
  if (!path_.empty()) unlink(path_.c_str());
}

void SpillFile::Append(const void* data, size_t bytes) {
  if (bytes == 0) return;
  if (fd_ < 0) {
    fd_ = open(path_.c_str(), O_RDWR | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
    if (fd_ < 0) {
      throw InputError(path_, "",
                       std::string("cannot create a spill file: ") + std::strerror(errno));
    }
  }
  const char* p = static_cast<const char*>(data);
  size_t left = bytes;
  while (left > 0) {
    const ssize_t w = write(fd_, p, left);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) {
      throw InputError(path_, "byte " + std::to_string(size_ + (bytes - left)),
                       std::string("cannot write a spill file: ") +
                           (w < 0 ? std::strerror(errno) : "no space written"));
    }
    p += w, left -= static_cast<size_t>(w);
  }
  size_ += bytes;
}

SpillFile::Mapping::~Mapping() {
  if (data_) munmap(data_, bytes_);
}

SpillFile::Mapping SpillFile::Map() const {
  if (size_ == 0) return Mapping(nullptr, 0);
  void* p = mmap(nullptr, static_cast<size_t>(size_), PROT_READ, MAP_PRIVATE, fd_, 0);
  if (p == MAP_FAILED) {
    throw InputError(path_, "", std::string("cannot map a spill file: ") + std::strerror(errno));
  }
  madvise(p, static_cast<size_t>(size_), MADV_SEQUENTIAL);
  return Mapping(p, static_cast<size_t>(size_));
}

void SpillFile::Read(uint64_t offset, size_t bytes, void* out) const {
  char* p = static_cast<char*>(out);
  while (bytes > 0) {
    const ssize_t got = pread(fd_, p, bytes, static_cast<off_t>(offset));
    if (got < 0 && errno == EINTR) continue;
    if (got <= 0) {
      throw InputError(path_, "byte " + std::to_string(offset), "cannot read a spill file back");
    }
    p += got, bytes -= static_cast<size_t>(got), offset += static_cast<uint64_t>(got);
  }
}

void SpillFile::Discard(uint64_t end) {
  constexpr uint64_t kBlock = uint64_t{1} << 20;  // whole MiB, so the blocks are the file's own
  end = end / kBlock * kBlock;
  if (fd_ < 0 || end <= discarded_) return;
  // Best effort: a filesystem without hole punching keeps the blocks until the file goes.
  if (fallocate(fd_, FALLOC_FL_PUNCH_HOLE | FALLOC_FL_KEEP_SIZE, static_cast<off_t>(discarded_),
                static_cast<off_t>(end - discarded_)) == 0) {
    discarded_ = end;
  }
}

}  // namespace candi

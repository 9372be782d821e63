#include "core/binary_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>

#include "core/check.h"

namespace candi {

int OpenForReading(const std::string& path, uint64_t* size, bool* regular) {
  const int fd = open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw InputError(path, "", std::string("cannot open: ") + std::strerror(errno));
  struct stat st;
  if (fstat(fd, &st) != 0) {
    const int err = errno;
    close(fd);
    throw InputError(path, "", std::string("cannot stat: ") + std::strerror(err));
  }
  if (S_ISDIR(st.st_mode)) {
    close(fd);
    throw InputError(path, "", "is a directory, not a file");
  }
  *size = static_cast<uint64_t>(st.st_size);
  if (regular) *regular = S_ISREG(st.st_mode);
  return fd;
}

BinaryFile::BinaryFile(const std::string& path) : path_(path) {
  fd_ = OpenForReading(path, &size_);
  posix_fadvise(fd_, 0, 0, POSIX_FADV_SEQUENTIAL);
}

BinaryFile::~BinaryFile() {
  if (fd_ >= 0) close(fd_);
}

void BinaryFile::Seek(uint64_t offset) {
  if (offset > size_) {
    throw InputError(path_, "byte " + std::to_string(offset),
                     "seek beyond the end of the file (" + std::to_string(size_) + " bytes)");
  }
  position_ = offset;
}

size_t BinaryFile::ReadAt(uint64_t offset, void* dst, size_t n) const {
  size_t total = 0;
  auto* out = static_cast<uint8_t*>(dst);
  while (total < n) {
    const ssize_t got = pread(fd_, out + total, n - total, static_cast<off_t>(offset + total));
    if (got < 0) {
      if (errno == EINTR) continue;
      throw InputError(path_, "byte " + std::to_string(offset + total),
                       std::string("read error: ") + std::strerror(errno));
    }
    if (got == 0) break;
    total += static_cast<size_t>(got);
  }
  return total;
}

size_t BinaryFile::ReadSome(void* dst, size_t n) {
  size_t total = 0;
  auto* out = static_cast<uint8_t*>(dst);
  while (total < n) {
    const ssize_t got = pread(fd_, out + total, n - total, static_cast<off_t>(position_));
    if (got < 0) {
      if (errno == EINTR) continue;
      throw InputError(path_, "byte " + std::to_string(position_),
                       std::string("read error: ") + std::strerror(errno));
    }
    if (got == 0) break;
    total += static_cast<size_t>(got);
    position_ += static_cast<uint64_t>(got);
  }
  return total;
}

void BinaryFile::ReadExact(void* dst, size_t n, const std::string& what) {
  const uint64_t start = position_;
  const size_t got = ReadSome(dst, n);
  if (got != n) {
    throw InputError(path_, "byte " + std::to_string(start),
                     "unexpected end of file while reading " + what + " (needed " +
                         std::to_string(n) + " bytes, " + std::to_string(got) + " left)");
  }
}

bool BinaryFile::ReadLine(std::string* line, size_t max_length) {
  line->clear();
  if (position_ >= size_) return false;
  char buf[256];
  while (true) {
    const uint64_t start = position_;
    const size_t got = ReadSome(buf, sizeof(buf));
    if (got == 0) return true;
    const char* nl = static_cast<const char*>(std::memchr(buf, '\n', got));
    const size_t take = nl ? static_cast<size_t>(nl - buf) : got;
    line->append(buf, take);
    if (line->size() > max_length) {
      throw InputError(path_, "byte " + std::to_string(start),
                       "line longer than " + std::to_string(max_length) + " bytes");
    }
    if (nl) {
      position_ = start + take + 1;
      if (!line->empty() && line->back() == '\r') line->pop_back();
      return true;
    }
  }
}

std::string BinaryFile::Peek(size_t n) const {
  std::string out(std::min<uint64_t>(n, size_), '\0');
  size_t total = 0;
  while (total < out.size()) {
    const ssize_t got = pread(fd_, out.data() + total, out.size() - total, total);
    if (got <= 0) break;
    total += static_cast<size_t>(got);
  }
  out.resize(total);
  return out;
}

}  // namespace candi

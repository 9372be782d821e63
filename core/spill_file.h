// SpillFile: a temporary file that work too large for memory is appended to and read back (the
// packer's cell files, a COPC file's records), deleted when the object goes.
//
// Created on the first Append (O_CREAT | O_TRUNC, mode 0600) and unlinked by the destructor; the
// folder it is in should be a temporary one registered with the interrupt handler
// (core/interrupt.h), so an interrupt leaves nothing behind. Appends go straight to the file (no
// buffer: callers append large runs). Map() gives the bytes read-only (MADV_SEQUENTIAL) while
// the mapping lives; Read() copies a range; Discard() gives the disk blocks of a prefix back
// (FALLOC_FL_PUNCH_HOLE where the filesystem has it), for a file that is read once from the
// start.
//
// Failure: InputError naming the file and the call (create, write: a full disk, map, read).
// Thread-safety: Append is not thread-safe; Map, Read and size may be used from several threads
// once the appends are done.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>

namespace candi {

class SpillFile {
 public:
  explicit SpillFile(std::string path) : path_(std::move(path)) {}
  ~SpillFile();
  SpillFile(const SpillFile&) = delete;
  SpillFile& operator=(const SpillFile&) = delete;

  void Append(const void* data, size_t bytes);
  uint64_t size() const { return size_; }
  const std::string& path() const { return path_; }

  // The bytes, mapped read-only while the Mapping lives.
  class Mapping {
   public:
    Mapping(void* data, size_t bytes) : data_(data), bytes_(bytes) {}
    ~Mapping();
    Mapping(const Mapping&) = delete;
    Mapping& operator=(const Mapping&) = delete;
    Mapping(Mapping&& o) noexcept : data_(o.data_), bytes_(o.bytes_) { o.data_ = nullptr; }
    const uint8_t* data() const { return static_cast<const uint8_t*>(data_); }
    size_t size() const { return bytes_; }

   private:
    void* data_;
    size_t bytes_;
  };
  Mapping Map() const;

  // Copies bytes [offset, offset + bytes) into out.
  void Read(uint64_t offset, size_t bytes, void* out) const;
  // The disk blocks wholly inside [0, end) are given back (their bytes read as zero after);
  // nothing where the filesystem cannot.
  void Discard(uint64_t end);

 private:
  std::string path_;
  int fd_ = -1;
  uint64_t size_ = 0, discarded_ = 0;
};

// A typed view of a SpillFile: records of type T (trivially copyable) appended and read back.
template <typename T>
class SpillRecords {
 public:
  explicit SpillRecords(std::string path) : file_(std::move(path)) {}
  void Append(const T* items, size_t n) { file_.Append(items, n * sizeof(T)); }
  uint64_t count() const { return file_.size() / sizeof(T); }
  SpillFile::Mapping Map() const { return file_.Map(); }
  // Reads items [from, from + n).
  void Read(uint64_t from, size_t n, T* out) const {
    file_.Read(from * sizeof(T), n * sizeof(T), out);
  }

 private:
  SpillFile file_;
};

}  // namespace candi

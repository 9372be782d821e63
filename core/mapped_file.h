// MappedFile: a whole file as read-only bytes in memory, for readers that decode records in
// parallel straight from the page cache (io/ply, io/las, io/xyz) instead of copying them into a
// buffer first.
//
// The file is mapped with mmap (PROT_READ, MAP_PRIVATE) and advised MADV_SEQUENTIAL and
// MADV_WILLNEED, so the kernel reads ahead while threads decode. Where mmap is refused (a pipe or
// FIFO, a character device, a filesystem without mmap, an empty file) the bytes are read into
// memory instead; mapped() says which. The size is 64-bit; a file larger than the address space
// is an error.
//
// Failure: InputError naming the path for a file that cannot be opened, is a directory, cannot be
// read, or is too large to address.
//
// A file that shrinks while it is mapped, or a disk error under a mapped page: touching the page
// raises SIGBUS (POSIX gives no portable way to turn it into an exception). CheckSize() makes the
// common case (a file truncated or rewritten between two reads) an InputError instead: readers
// call it before decoding a range. A file truncated during one decode, or a failing disk, still
// raises SIGBUS; a program that calls InstallMappedFileFaultHandler() (candi's main does) then
// ends with "<path>: byte <n>: the file was cut short or could not be read from the disk while
// it was read" on stderr and exit status 2, like any bad input, instead of a crash. The outputs
// it was writing are left as they were (temporaries beside them may remain).
//
// Thread-safety: data() may be read from any number of threads; the object is immutable after
// construction.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace candi {

class MappedFile {
 public:
  explicit MappedFile(const std::string& path);
  ~MappedFile();
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  const std::string& path() const { return path_; }
  const uint8_t* data() const { return data_; }
  uint64_t size() const { return size_; }
  bool mapped() const { return mapped_; }  // false: the bytes were read into memory

  // Throws InputError "<path>: byte <size now>: the file shrank to ... while it was read (needed
  // <end> bytes for <what>)" when the file on disk is now shorter than `end` bytes; a file read
  // into memory never shrinks.
  void CheckSize(uint64_t end, const std::string& what) const;
  // A hint that [offset, offset + n) is read soon (MADV_WILLNEED); nothing for a file in memory.
  void WillNeed(uint64_t offset, uint64_t n) const;

 private:
  void ReadIntoMemory();

  friend std::shared_ptr<const MappedFile> MapShared(const std::string& path);

  std::string path_;
  int fd_ = -1;
  uint64_t device_ = 0, inode_ = 0;
  int64_t modified_ns_ = 0;  // the file's identity when it was mapped
  const uint8_t* data_ = nullptr;
  uint64_t size_ = 0;
  bool mapped_ = false;
  int range_ = -1;               // its slot in the SIGBUS handler's table
  std::vector<uint8_t> memory_;  // the bytes when not mapped
};

// The mapping of `path` that another holder still has, if the file is still the one it mapped
// (the same device, inode, size and modification time), else a new MappedFile. Passes that read
// one file at the same time (the packer's hash of an input and its records, on two threads) then
// map its pages once: mapping and unmapping a 2.6 GB file costs ~0.3 CPU-s on the project's VM
// (page tables set up by fault-around, then torn down). Only mapped regular files are shared; a
// pipe read into memory is not (it can be read once). Thread-safe.
std::shared_ptr<const MappedFile> MapShared(const std::string& path);

// Installs the SIGBUS handler described above (idempotent). Faults outside every mapped file
// keep the default action.
void InstallMappedFileFaultHandler();

}  // namespace candi

// AtomicFile: write a file so that the destination is either the old file or the complete new one.
//
// Data goes to a temporary file beside the destination ("<path>.candi-tmp-XXXXXX"); Commit()
// flushes, checks every write, closes and renames it over the destination. If anything fails, or
// the object is destroyed without Commit(), the temporary is removed and the destination is left
// as it was. Errors throw InputError naming the path and the OS reason (disk full, permission).
// An interrupt (core/interrupt.h) removes the temporary too.
// Not thread-safe.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

namespace candi {

class AtomicFile {
 public:
  explicit AtomicFile(const std::string& path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  void Write(const void* data, size_t size);
  void Write(const std::string& text) { Write(text.data(), text.size()); }
  // Overwrites `size` bytes at absolute `offset` (header patching); the write position is kept.
  void WriteAt(uint64_t offset, const void* data, size_t size);
  uint64_t Tell() const { return written_; }
  // Preallocates `bytes` for the file (a hint: fails silently where unsupported). On ext4 this
  // roughly doubles write throughput, and a disk that cannot hold the file fails here, early,
  // with InputError (ENOSPC) instead of after gigabytes.
  void Reserve(uint64_t bytes);
  void Commit();

  const std::string& path() const { return path_; }
  const std::string& temp_path() const { return temp_path_; }

 private:
  void Fail(const std::string& what, int err);
  void Discard();

  std::string path_, temp_path_;
  FILE* file_ = nullptr;
  uint64_t written_ = 0;
  bool committed_ = false;
  int interrupt_id_ = -1;  // core/interrupt.h: removed if the process is interrupted
};

// Writes `contents` to `path` atomically.
void WriteFileAtomic(const std::string& path, const std::string& contents);

// Reads a whole file; throws InputError naming the path.
std::string ReadFileToString(const std::string& path);

// Throws InputError naming `output` when its folder does not exist or is not writable: an early
// check, so that a long command fails before its work, not after it.
void CheckOutputFolder(const std::string& output);

// Throws InputError naming `output` unless ReplaceFolder could put a folder there: `output` may
// be absent or what `replaceable` accepts, never a symbolic link (the link would be replaced by a
// real folder while the folder it points to kept its old contents), and its folder must be
// writable. An early check, so that a long command fails before its work.
void CheckReplaceableFolder(const std::string& output, bool (*replaceable)(const std::string&),
                            const std::string& what);

// Renames the folder `temp` (built beside `output`) to `output`. Something already at `output`
// is replaced only when `replaceable(output)` says it is what this command writes (moved aside
// as "<output>.candi-old-<pid>", the new one renamed in, the old one removed; put back if the
// rename fails); anything else, and a symbolic link, is refused with InputError. When the old
// one cannot be removed, a warning names the copy left behind.
void ReplaceFolder(const std::string& temp, const std::string& output, bool (*replaceable)(const std::string&),
                   const std::string& what);

}  // namespace candi

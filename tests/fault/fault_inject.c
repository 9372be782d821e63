// A preloaded library (LD_PRELOAD) that makes reads of one file fail mid-way, as a failing disk
// or a dropped network share does: tests/fault_test.cc runs candi with it.
//
// CANDI_FAULT_READ=<path suffix>:<offset>  every read()/pread() of a file whose path ends with
// the suffix that reaches byte <offset> or beyond fails with EIO (bytes before it read normally),
// and mmap() of such a range fails with ENODEV, as on a filesystem that refuses mapping: the
// readers that map files (core/mapped_file.h) then read them, and meet the failing read. (A real
// I/O error under a mapping is a SIGBUS, which this library cannot simulate.)
//
// CANDI_FAULT_REMOVE=<text>  every unlink(), unlinkat(), rmdir() and remove() of a path holding
// the text fails with EBUSY, as removing a folder a process still uses on a network share can: a
// removal that runs as root cannot be refused by permissions alone.
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/types.h>
#include <unistd.h>

static int Faulty(int fd, off_t end) {
  const char* spec = getenv("CANDI_FAULT_READ");
  if (spec == NULL) return 0;
  const char* colon = strrchr(spec, ':');
  if (colon == NULL) return 0;
  const size_t suffix_length = (size_t)(colon - spec);
  const long long offset = atoll(colon + 1);
  if (end <= offset) return 0;
  char link[64], path[4096];
  snprintf(link, sizeof(link), "/proc/self/fd/%d", fd);
  const ssize_t n = readlink(link, path, sizeof(path) - 1);
  if (n < 0 || (size_t)n < suffix_length) return 0;
  return memcmp(path + n - suffix_length, spec, suffix_length) == 0;
}

typedef ssize_t (*PreadFn)(int, void*, size_t, off_t);
typedef ssize_t (*ReadFn)(int, void*, size_t);

static ssize_t FaultyPread(PreadFn* real, const char* name, int fd, void* buf, size_t count, off_t offset) {
  if (*real == NULL) *real = (PreadFn)dlsym(RTLD_NEXT, name);
  if (Faulty(fd, offset + (off_t)count)) {
    errno = EIO;
    return -1;
  }
  return (*real)(fd, buf, count, offset);
}

ssize_t pread(int fd, void* buf, size_t count, off_t offset) {
  static PreadFn real = NULL;
  return FaultyPread(&real, "pread", fd, buf, count, offset);
}

ssize_t pread64(int fd, void* buf, size_t count, off_t offset) {
  static PreadFn real = NULL;
  return FaultyPread(&real, "pread64", fd, buf, count, offset);
}

ssize_t read(int fd, void* buf, size_t count) {
  static ReadFn real = NULL;
  if (real == NULL) real = (ReadFn)dlsym(RTLD_NEXT, "read");
  const off_t at = lseek(fd, 0, SEEK_CUR);
  if (at >= 0 && Faulty(fd, at + (off_t)count)) {
    errno = EIO;
    return -1;
  }
  return real(fd, buf, count);
}

typedef void* (*MmapFn)(void*, size_t, int, int, int, off_t);

static void* FaultyMmap(MmapFn* real, const char* name, void* addr, size_t length, int prot, int flags,
                        int fd, off_t offset) {
  if (*real == NULL) *real = (MmapFn)dlsym(RTLD_NEXT, name);
  if (fd >= 0 && Faulty(fd, offset + (off_t)length)) {
    errno = ENODEV;
    return MAP_FAILED;
  }
  return (*real)(addr, length, prot, flags, fd, offset);
}

void* mmap(void* addr, size_t length, int prot, int flags, int fd, off_t offset) {
  static MmapFn real = NULL;
  return FaultyMmap(&real, "mmap", addr, length, prot, flags, fd, offset);
}

void* mmap64(void* addr, size_t length, int prot, int flags, int fd, off_t offset) {
  static MmapFn real = NULL;
  return FaultyMmap(&real, "mmap64", addr, length, prot, flags, fd, offset);
}

// ---- CANDI_FAULT_REMOVE ----------------------------------------------------------------------

#include <fcntl.h>

static int Unremovable(int dirfd, const char* path) {
  const char* text = getenv("CANDI_FAULT_REMOVE");
  if (text == NULL || *text == '\0' || path == NULL) return 0;
  if (strstr(path, text) != NULL) return 1;
  if (path[0] == '/' || dirfd == AT_FDCWD) return 0;
  char link[64], dir[4096];
  snprintf(link, sizeof(link), "/proc/self/fd/%d", dirfd);
  const ssize_t n = readlink(link, dir, sizeof(dir) - 1);
  if (n < 0) return 0;
  dir[n] = '\0';
  return strstr(dir, text) != NULL;
}

typedef int (*PathFn)(const char*);
typedef int (*AtFn)(int, const char*, int);

static int Remove(const char* name, PathFn* real, const char* path) {
  if (*real == NULL) *real = (PathFn)dlsym(RTLD_NEXT, name);
  if (Unremovable(AT_FDCWD, path)) {
    errno = EBUSY;
    return -1;
  }
  return (*real)(path);
}

int unlink(const char* path) {
  static PathFn real = NULL;
  return Remove("unlink", &real, path);
}

int rmdir(const char* path) {
  static PathFn real = NULL;
  return Remove("rmdir", &real, path);
}

int remove(const char* path) {
  static PathFn real = NULL;
  return Remove("remove", &real, path);
}

int unlinkat(int dirfd, const char* path, int flags) {
  static AtFn real = NULL;
  if (real == NULL) real = (AtFn)dlsym(RTLD_NEXT, "unlinkat");
  if (Unremovable(dirfd, path)) {
    errno = EBUSY;
    return -1;
  }
  return real(dirfd, path, flags);
}

#include "core/mapped_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#include "core/check.h"
#include "tests/util/test_util.h"

namespace candi {
namespace {

using testing::TempDir;
using testing::WriteBytes;

TEST(MappedFile, HoldsTheFilesBytes) {
  TempDir dir;
  const std::string path = dir.File("a.bin");
  std::string bytes(100000, '\0');
  for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>(i * 7);
  WriteBytes(path, bytes);
  const MappedFile map(path);
  EXPECT_TRUE(map.mapped());
  ASSERT_EQ(map.size(), bytes.size());
  EXPECT_EQ(std::memcmp(map.data(), bytes.data(), bytes.size()), 0);
  map.WillNeed(4096, 1 << 20);  // beyond the end: clipped
  map.CheckSize(map.size(), "everything");
}

TEST(MappedFile, EmptyFileHasNoBytes) {
  TempDir dir;
  WriteBytes(dir.File("e"), "");
  const MappedFile map(dir.File("e"));
  EXPECT_EQ(map.size(), 0u);
  EXPECT_FALSE(map.mapped());
}

// A FIFO cannot be mapped: its bytes are read into memory until the writer closes it.
TEST(MappedFile, PipeIsReadIntoMemory) {
  TempDir dir;
  const std::string path = dir.File("fifo");
  ASSERT_EQ(mkfifo(path.c_str(), 0600), 0);
  const std::string bytes(300000, 'p');
  std::thread writer([&] { WriteBytes(path, bytes); });
  const MappedFile map(path);
  writer.join();
  EXPECT_FALSE(map.mapped());
  ASSERT_EQ(map.size(), bytes.size());
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(map.data()), map.size()), bytes);
}

TEST(MappedFile, FileThatShrankIsAnErrorNamingThePath) {
  TempDir dir;
  const std::string path = dir.File("s.bin");
  WriteBytes(path, std::string(50000, 's'));
  const MappedFile map(path);
  std::filesystem::resize_file(path, 100);
  try {
    map.CheckSize(20000, "records");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), path +
                                         ": byte 100: the file shrank from 50000 to 100 bytes "
                                         "while it was read (needed 20000 bytes for records)");
  }
  map.CheckSize(100, "the rest");  // what is left is fine
}

// A mapped file cut short while it is read (after CheckSize could see it): with the handler the
// process ends with status 2 and a message naming the file and the byte, not a crash. In a child
// process, so that the fault is real.
TEST(MappedFile, AFaultUnderTheMapIsAnErrorNamingTheFileAndByte) {
  TempDir dir;
  const std::string path = dir.File("cut.bin");
  WriteBytes(path, std::string(5 * 4096, 'x'));
  int err[2];
  ASSERT_EQ(pipe(err), 0);
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    dup2(err[1], 2);
    InstallMappedFileFaultHandler();
    const MappedFile map(path);
    if (truncate(path.c_str(), 4096) != 0) _exit(5);
    volatile uint8_t sink = map.data()[3 * 4096 + 7];  // a page past the new end
    (void)sink;
    _exit(0);
  }
  close(err[1]);
  std::string message;
  char buffer[512];
  for (ssize_t got; (got = read(err[0], buffer, sizeof(buffer))) > 0;) message.append(buffer, static_cast<size_t>(got));
  close(err[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status)) << "ended by signal " << WTERMSIG(status) << ": " << message;
  EXPECT_EQ(WEXITSTATUS(status), 2) << message;
  EXPECT_EQ(message, path + ": byte 12295: the file was cut short or could not be read from the disk while it was "
                            "read; the outputs are as they were\n");
}

TEST(MapShared, ALiveMapOfTheSameFileIsSharedAndAChangedFileIsMappedAfresh) {
  TempDir dir;
  const std::string path = dir.File("a.bin");
  WriteBytes(path, std::string(50000, 'a'));
  std::shared_ptr<const MappedFile> first = MapShared(path);
  EXPECT_EQ(MapShared(path), first);  // held: the same map
  const uint8_t* const data = first->data();
  // Replaced under the same name (a new inode): its own map, with the new bytes.
  WriteBytes(dir.File("tmp"), std::string(50000, 'b'));
  std::filesystem::rename(dir.File("tmp"), path);
  std::shared_ptr<const MappedFile> second = MapShared(path);
  EXPECT_NE(second, first);
  EXPECT_EQ(second->data()[0], 'b');
  EXPECT_EQ(first->data(), data);
  EXPECT_EQ(first->data()[0], 'a');  // the old map still holds the old file
  // Rewritten to another size: not shared either.
  WriteBytes(path, std::string(60000, 'c'));
  std::shared_ptr<const MappedFile> third = MapShared(path);
  EXPECT_NE(third, second);
  EXPECT_EQ(third->size(), 60000u);
  // Released: nothing keeps it alive, and the next call maps the file again.
  std::weak_ptr<const MappedFile> gone = third;
  third.reset();
  EXPECT_TRUE(gone.expired());
  EXPECT_EQ(MapShared(path)->size(), 60000u);
}

TEST(MapShared, APipeIsNotShared) {
  TempDir dir;
  const std::string fifo = dir.File("fifo");
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  auto read_one = [&](const std::string& bytes) {
    std::thread writer([&] { WriteBytes(fifo, bytes); });
    std::shared_ptr<const MappedFile> map = MapShared(fifo);
    writer.join();
    return map;
  };
  const std::shared_ptr<const MappedFile> a = read_one("first bytes");
  const std::shared_ptr<const MappedFile> b = read_one("second bytes");  // a still held: not shared
  EXPECT_FALSE(a->mapped());
  EXPECT_NE(a, b);
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(a->data()), a->size()), "first bytes");
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(b->data()), b->size()), "second bytes");
}

TEST(MappedFile, MissingFileAndDirectoryAreErrorsNamingThePath) {
  TempDir dir;
  EXPECT_THROW(MappedFile(dir.File("none")), InputError);
  try {
    MappedFile m(dir.path());
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(dir.path()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace candi

#include "core/mapped_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstring>
#include <filesystem>
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

#include "io/byte_stream.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string>

#include "core/binary_file.h"
#include "tests/util/test_util.h"

namespace candi::io {
namespace {

using testing::TempDir;
using testing::WriteBytes;

// Fills of many megabytes are copied by parallel parts: the bytes must be those of one read, in
// order, and a fill past the end must stop there with what is left available.
TEST(ByteStream, LargeFillsInPartsEqualTheFileAndStopAtItsEnd) {
  TempDir dir;
  std::string bytes(size_t{20} << 20, '\0');
  for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>((i * 2654435761u) >> 24);
  WriteBytes(dir.File("b.bin"), bytes);
  BinaryFile file(dir.File("b.bin"));
  file.Seek(3);  // not on a part boundary
  ByteStream stream(file, size_t{1} << 20);
  ASSERT_TRUE(stream.Ensure(size_t{12} << 20));
  EXPECT_EQ(std::memcmp(stream.data(), bytes.data() + 3, size_t{12} << 20), 0);
  stream.Consume(size_t{5} << 20);
  ASSERT_TRUE(stream.Ensure(size_t{14} << 20));  // keeps the 7 MB left, reads 7 MB more
  EXPECT_EQ(stream.offset(), 3 + (size_t{5} << 20));
  EXPECT_EQ(std::memcmp(stream.data(), bytes.data() + stream.offset(), size_t{14} << 20), 0);
  EXPECT_FALSE(stream.Ensure(size_t{30} << 20));
  const size_t left = bytes.size() - stream.offset();
  ASSERT_EQ(stream.available(), left);
  EXPECT_EQ(std::memcmp(stream.data(), bytes.data() + stream.offset(), left), 0);
  EXPECT_TRUE(stream.Ensure(left));
  stream.Consume(left);
  EXPECT_TRUE(stream.AtEnd());
}

}  // namespace
}  // namespace candi::io

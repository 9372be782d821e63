#include "core/sha256.h"

#include <gtest/gtest.h>

#include "core/check.h"
#include "tests/util/test_util.h"

namespace candi {
namespace {

// FIPS 180-4 examples and the NIST one-million-'a' vector.
TEST(Sha256, KnownVectors) {
  EXPECT_EQ(Sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(Sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(Sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(Sha256Hex(std::string(1000000, 'a')),
            "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
}

TEST(Sha256, StreamingAndFilesAgreeWithOneShot) {
  std::string bytes;
  for (int i = 0; i < 3000; ++i) bytes += static_cast<char>(i * 7 + i / 13);
  Sha256 pieces;
  for (size_t at = 0, step = 1; at < bytes.size(); at += step, step = step % 97 + 1)
    pieces.Update(bytes.data() + at, std::min(step, bytes.size() - at));
  EXPECT_EQ(pieces.HexDigest(), Sha256Hex(bytes));
  testing::TempDir dir;
  testing::WriteBytes(dir.File("f.bin"), bytes);
  EXPECT_EQ(Sha256OfFile(dir.File("f.bin")), Sha256Hex(bytes));
  EXPECT_THROW(Sha256OfFile(dir.File("missing.bin")), InputError);
}

}  // namespace
}  // namespace candi

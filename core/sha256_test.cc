#include "core/sha256.h"

#include <gtest/gtest.h>

#include "core/check.h"
#include "core/rng.h"
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

// coreutils' sha256sum as an independent reference, on a file of several 1 MiB reads whose size is
// no multiple of the 64-byte block.
TEST(Sha256, FileAgreesWithSha256sum) {
  std::string bytes(5 * 1048576 + 37, '\0');
  Rng rng(11);
  for (char& c : bytes) c = static_cast<char>(rng.Next() >> 56);
  testing::TempDir dir;
  testing::WriteBytes(dir.File("big.bin"), bytes);
  const testing::CommandResult sum = testing::RunCommand("sha256sum " + dir.File("big.bin"));
  ASSERT_EQ(sum.code, 0) << sum.output;
  EXPECT_EQ(Sha256OfFile(dir.File("big.bin")), sum.out.substr(0, 64));
}

TEST(Sha256, MovedObjectKeepsItsState) {
  Sha256 a;
  a.Update("ab", 2);
  Sha256 b = std::move(a);
  b.Update("c", 1);
  EXPECT_EQ(b.HexDigest(), Sha256Hex("abc"));
}

}  // namespace
}  // namespace candi

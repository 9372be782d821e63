#include "core/base64.h"

#include <gtest/gtest.h>

#include <string>

namespace candi {
namespace {

// RFC 4648, section 10: the encodings of the prefixes of "foobar".
TEST(Base64, TestVectorsOfTheRfc) {
  const std::string foobar = "foobar";
  const std::string text[] = {"", "Zg==", "Zm8=", "Zm9v", "Zm9vYg==", "Zm9vYmE=", "Zm9vYmFy"};
  for (size_t n = 0; n <= foobar.size(); ++n) EXPECT_EQ(Base64(foobar.substr(0, n)), text[n]) << n;
}

TEST(Base64, EveryByteValue) {
  std::string bytes;
  for (int b = 0; b < 256; ++b) bytes += static_cast<char>(b);
  const std::string text = Base64(bytes);
  EXPECT_EQ(text.size(), 344u);
  EXPECT_EQ(text.substr(0, 8), "AAECAwQF");
  EXPECT_EQ(text.substr(text.size() - 8), "/P3+/w==");
}

}  // namespace
}  // namespace candi

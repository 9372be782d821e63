// FreshBuffer keeps what was appended across its growth; FaultInParallel leaves the bytes around
// its range alone (the pages at its ends are shared with them).
#include "core/fresh_memory.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace candi {
namespace {

TEST(FreshBuffer, KeepsWhatWasAppendedAcrossItsGrowth) {
  FreshBuffer buffer;
  std::vector<uint8_t> expected;
  std::vector<uint8_t> piece(3 * 1000 * 1000 + 7);  // not a multiple of a page
  for (int round = 0; round < 50; ++round) {         // 150 MB: grows past 64 MiB, then doubles
    for (size_t i = 0; i < piece.size(); ++i) piece[i] = static_cast<uint8_t>(i * 31 + round);
    buffer.Append(piece.data(), piece.size());
    expected.insert(expected.end(), piece.begin(), piece.end());
  }
  ASSERT_EQ(buffer.size(), expected.size());
  EXPECT_EQ(std::vector<uint8_t>(buffer.data(), buffer.data() + buffer.size()), expected);
  buffer.Reserve(buffer.size() + 1);  // a copy into fresh pages
  EXPECT_EQ(std::vector<uint8_t>(buffer.data(), buffer.data() + buffer.size()), expected);
  buffer.Release();
  EXPECT_EQ(buffer.size(), 0u);
  EXPECT_EQ(buffer.data(), nullptr);
  buffer.Append(piece.data(), 10);
  EXPECT_EQ(buffer.data()[9], piece[9]);
  uint8_t* tail = buffer.Extend(5);  // the next five bytes, to be written in place
  EXPECT_EQ(tail, buffer.data() + 10);
  EXPECT_EQ(buffer.size(), 15u);
}

TEST(FaultInParallel, LeavesTheBytesAroundItsRangeAlone) {
  std::vector<uint8_t> bytes(9 * 1000 * 1000);
  for (size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<uint8_t>(i % 251 + 1);
  const size_t from = 1234, to = bytes.size() - 4321;
  FaultInParallel(bytes.data() + from, to - from);
  for (size_t i = 0; i < from; ++i) ASSERT_EQ(bytes[i], i % 251 + 1) << i;
  for (size_t i = to; i < bytes.size(); ++i) ASSERT_EQ(bytes[i], i % 251 + 1) << i;
  FaultInParallel(bytes.data(), 0);  // nothing
}

}  // namespace
}  // namespace candi

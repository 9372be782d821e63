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

TEST(ReserveHuge, GrowsOnlyWhenNeededAndTheMemoryHoldsWhatIsWritten) {
  std::vector<uint64_t> v;
  ReserveHuge(&v, 0);
  ReserveHuge(&v, 3'000'000);  // 24 MB: whole 2 MiB pages inside, advised
  ASSERT_GE(v.capacity(), 3'000'000u);
  const uint64_t* const first = v.data();
  v.resize(3'000'000);
  for (size_t i = 0; i < v.size(); ++i) v[i] = i * 0x9E3779B97F4A7C15ull;
  ReserveHuge(&v, 3'500'000);  // within the quarter more: kept, contents and all
  EXPECT_EQ(v.data(), first);
  EXPECT_EQ(v.size(), 3'000'000u);
  for (size_t i = 0; i < v.size(); i += 4099) ASSERT_EQ(v[i], i * 0x9E3779B97F4A7C15ull) << i;
  ReserveHuge(&v, 5'000'000);  // grown: its elements dropped
  EXPECT_GE(v.capacity(), 5'000'000u);
  EXPECT_TRUE(v.empty());
  v.assign(5'000'000, 7);
  EXPECT_EQ(v[4'999'999], 7u);
  // Ranges with no whole huge page, or none at all, are left alone.
  uint8_t small[100] = {1};
  AdviseHugePages(small, sizeof(small));
  AdviseHugePages(nullptr, 0);
  EXPECT_EQ(small[0], 1);
}

}  // namespace
}  // namespace candi

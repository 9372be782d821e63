#include "render/morton_sort.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <string>
#include <vector>

#include "core/rng.h"

namespace candi::render {
namespace {

// n keys whose codes have `bits` random low bits (few distinct values when `values` is small,
// so ties are common) over a common high part; index = input position.
std::vector<Keyed> RandomKeys(size_t n, int bits, uint64_t values, uint64_t seed) {
  Rng rng(seed);
  const uint64_t low_mask = bits >= 64 ? ~uint64_t{0} : (uint64_t{1} << bits) - 1;
  const uint64_t high = 0x5a5aull << 48 & ~low_mask;
  std::vector<Keyed> keys(n);
  for (size_t i = 0; i < n; ++i) {
    const uint64_t v = values ? HashIndex(seed, rng.Below(values)) : rng.Next();
    keys[i] = {high | (v & low_mask), static_cast<uint32_t>(i)};
  }
  return keys;
}

std::vector<Keyed> Reference(std::vector<Keyed> keys, int bits) {
  const uint64_t mask = bits >= 64 ? ~uint64_t{0} : (uint64_t{1} << bits) - 1;
  std::stable_sort(keys.begin(), keys.end(),
                   [mask](const Keyed& a, const Keyed& b) { return (a.code & mask) < (b.code & mask); });
  return keys;
}

bool Same(const std::vector<Keyed>& a, const std::vector<Keyed>& b) {
  return a.size() == b.size() && std::equal(a.begin(), a.end(), b.begin(), [](const Keyed& x, const Keyed& y) {
           return x.code == y.code && x.index == y.index;
         });
}

TEST(SortByCode, EqualsAStableSortForAnyBitsSizeAndThreads) {
  struct Case {
    size_t n;
    int bits;
    uint64_t values;  // 0: all distinct (random)
  };
  for (const Case& c : {Case{0, 54, 0}, Case{1, 54, 0}, Case{2, 0, 0}, Case{1000, 5, 0}, Case{5000, 11, 0},
                        Case{5000, 12, 0}, Case{30000, 54, 0}, Case{30000, 63, 7}, Case{30000, 64, 0},
                        Case{100000, 40, 300}, Case{20000, 54, 1}}) {
    const std::vector<Keyed> input = RandomKeys(c.n, c.bits, c.values, 17 + c.n + c.bits);
    const std::vector<Keyed> expected = Reference(input, c.bits);
    for (int threads : {1, 2}) {
      std::vector<Keyed> keys = input, scratch;
      tbb::task_arena(threads).execute([&] { SortByCode(&keys, &scratch, c.bits); });
      EXPECT_TRUE(Same(keys, expected)) << c.n << " keys, " << c.bits << " bits, " << c.values << " values, "
                                        << threads << " threads";
    }
  }
}

TEST(SortByCode, CoarseSortOrdersEveryNodeOfMoreKeysThanCoarse) {
  // Clustered codes (few values in the low levels for some keys) so that nodes of every size
  // occur, at 12 to 63 bits; coarse around the node sizes.
  for (const int bits : {12, 27, 63}) {
    for (const size_t coarse : {size_t{1}, size_t{40}, size_t{700}}) {
      std::vector<Keyed> input = RandomKeys(20000, bits, 0, 5 + bits + coarse);
      for (size_t i = 0; i < input.size(); i += 3) input[i].code &= ~uint64_t{0} << (bits > 15 ? bits - 15 : 0);
      std::vector<Keyed> keys = input, scratch, again = input;
      SortByCode(&keys, &scratch, bits, coarse);
      tbb::task_arena(1).execute([&] { SortByCode(&again, &scratch, bits, coarse); });
      const std::string what = std::to_string(bits) + " bits, coarse " + std::to_string(coarse);
      EXPECT_TRUE(Same(keys, again)) << what << ": 1 thread and default differ";
      // A permutation of the input.
      std::vector<uint32_t> seen;
      for (const Keyed& k : keys) seen.push_back(k.index);
      std::sort(seen.begin(), seen.end());
      for (size_t i = 0; i < seen.size(); ++i) ASSERT_EQ(seen[i], i) << what;
      for (const Keyed& k : keys) ASSERT_EQ(k.code, input[k.index].code) << what;
      // Level by level: within every node of more than `coarse` keys (contiguous, by the level
      // above), its children's prefixes never decrease; equal codes keep their input order.
      for (int level = 1; level <= bits / 3; ++level) {
        auto prefix = [&](const Keyed& k, int l) { return l == 0 ? 0 : k.code >> (bits - 3 * l); };
        std::map<uint64_t, size_t> parent_size;
        for (const Keyed& k : keys) ++parent_size[prefix(k, level - 1)];
        for (size_t i = 0; i + 1 < keys.size(); ++i) {
          if (prefix(keys[i], level - 1) != prefix(keys[i + 1], level - 1)) continue;
          if (parent_size[prefix(keys[i], level - 1)] <= coarse) continue;
          ASSERT_LE(prefix(keys[i], level), prefix(keys[i + 1], level)) << what << ", level " << level << ", key " << i;
        }
        // Nodes of more than `coarse` keys are contiguous.
        std::map<uint64_t, std::pair<size_t, size_t>> span;
        for (size_t i = 0; i < keys.size(); ++i) {
          const auto it = span.try_emplace(prefix(keys[i], level), i, i).first;
          it->second.second = i;
        }
        std::map<uint64_t, size_t> size;
        for (const Keyed& k : keys) ++size[prefix(k, level)];
        for (const auto& [p, s] : span) {
          if (size[p] > coarse) {
            ASSERT_EQ(s.second - s.first + 1, size[p]) << what << ", level " << level;
          }
        }
      }
      for (size_t i = 0; i + 1 < keys.size(); ++i) {
        if (keys[i].code == keys[i + 1].code) {
          ASSERT_LT(keys[i].index, keys[i + 1].index) << what;
        }
      }
    }
  }
}

TEST(SortByCode, LooksOnlyAtTheLowBits) {
  // Codes that differ above `bits` keep their input order when their low bits tie.
  std::vector<Keyed> keys = {{0x300, 0}, {0x101, 1}, {0x200, 2}, {0x001, 3}}, scratch;
  SortByCode(&keys, &scratch, 8);
  const std::vector<uint64_t> order = {0, 2, 1, 3};
  for (size_t i = 0; i < keys.size(); ++i) EXPECT_EQ(keys[i].index, order[i]) << i;
}

TEST(SortByCode, RecordsFollowTheirKeys) {
  // Records of 16, 28 and 12 bytes (the fixed sizes and any other), each filled from its input
  // position; keys whose index is their position (the packer's) or a permutation of it; full,
  // coarse and no sorts (too few keys, no bits), on 1 and 2 threads.
  struct Case {
    size_t n;
    int bits;
    size_t coarse;
  };
  for (const Case& c : {Case{30000, 54, 0}, Case{30000, 63, 40}, Case{20000, 27, 700}, Case{500, 27, 700},
                        Case{3000, 0, 0}, Case{1, 54, 0}}) {
    for (const size_t bytes : {size_t{16}, size_t{28}, size_t{12}}) {
      for (const bool permuted : {false, true}) {
        std::vector<Keyed> input = RandomKeys(c.n, c.bits, c.n / 20, 3 + c.n + bytes);
        // Clustered low levels for a third of the keys, so that some coarse buckets are sorted.
        for (size_t i = 0; i < input.size(); i += 3) input[i].code &= ~uint64_t{0} << (c.bits > 15 ? c.bits - 15 : 0);
        if (permuted) {
          Rng rng(c.n + bytes);
          for (size_t i = input.size(); i > 1; --i) std::swap(input[i - 1].index, input[rng.Below(i)].index);
        }
        std::vector<unsigned char> records(c.n * bytes);
        for (size_t i = 0; i < records.size(); ++i) records[i] = static_cast<unsigned char>(HashIndex(bytes, i));
        std::vector<Keyed> expected = input, scratch;
        SortByCode(&expected, &scratch, c.bits, c.coarse);
        for (int threads : {1, 2}) {
          std::vector<Keyed> keys = input;
          std::vector<unsigned char> sorted(records.size(), 0);
          tbb::task_arena(threads).execute(
              [&] { SortByCode(&keys, &scratch, c.bits, c.coarse, records.data(), bytes, sorted.data()); });
          const std::string what = std::to_string(c.n) + " keys, " + std::to_string(c.bits) + " bits, coarse " +
                                   std::to_string(c.coarse) + ", " + std::to_string(bytes) + "-byte records, " +
                                   (permuted ? "permuted" : "in order") + ", " + std::to_string(threads) + " threads";
          ASSERT_TRUE(Same(keys, expected)) << what;
          for (size_t j = 0; j < keys.size(); ++j) {
            ASSERT_EQ(0, std::memcmp(&sorted[j * bytes], &records[keys[j].index * bytes], bytes)) << what << ", key " << j;
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace candi::render

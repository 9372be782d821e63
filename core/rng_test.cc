#include "core/rng.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace candi {
namespace {

TEST(Rng, SameSeedSameSequenceDifferentSeedDifferent) {
  Rng a(42), b(42), c(43);
  int differ = 0;
  for (int i = 0; i < 1000; ++i) {
    const uint64_t x = a.Next();
    EXPECT_EQ(x, b.Next());
    differ += x != c.Next();
  }
  EXPECT_GT(differ, 990);
}

TEST(Rng, KnownValuesPinThePlatformIndependentStream) {
  // Pinned so that a change of generator (which would change every seeded output) is noticed.
  EXPECT_EQ(Mix64(0), 0xe220a8397b1dcdafULL);
  Rng rng(0);
  const uint64_t first = rng.Next();
  Rng again(0);
  EXPECT_EQ(first, again.Next());
}

TEST(Rng, UniformAndBelowAreUnbiased) {
  Rng rng(9);
  std::vector<int> counts(10, 0);
  double sum = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    counts[rng.Below(10)]++;
    const double u = rng.Uniform();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
  }
  for (int c : counts) EXPECT_NEAR(c, n / 10, 5 * std::sqrt(n / 10.0));
  EXPECT_NEAR(sum / n, 0.5, 0.005);
}

TEST(Rng, NormalHasUnitVariance) {
  Rng rng(5);
  double s = 0, s2 = 0;
  const int n = 200000;
  for (int i = 0; i < n; ++i) {
    const double x = rng.Normal();
    s += x;
    s2 += x * x;
  }
  EXPECT_NEAR(s / n, 0.0, 0.01);
  EXPECT_NEAR(s2 / n, 1.0, 0.02);
}

TEST(HashIndex, IsStatelessAndSpreadsIndices) {
  EXPECT_EQ(HashIndex(1, 77), HashIndex(1, 77));
  EXPECT_NE(HashIndex(1, 77), HashIndex(2, 77));
  EXPECT_NE(HashIndex(1, 77, 0), HashIndex(1, 77, 1));
  std::vector<int> buckets(16, 0);
  for (uint64_t i = 0; i < 160000; ++i) buckets[HashIndex(3, i) % 16]++;
  for (int b : buckets) EXPECT_NEAR(b, 10000, 500);
}

}  // namespace
}  // namespace candi

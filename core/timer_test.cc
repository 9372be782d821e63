#include "core/timer.h"

#include <gtest/gtest.h>

namespace candi {
namespace {

// Laps add up to the total (no interval is counted twice or lost); times never run backwards.
TEST(Stopwatch, LapsAddUpToTheTotal) {
  Stopwatch watch;
  double laps = 0;
  for (int i = 0; i < 3; ++i) {
    volatile double sink = 0;
    for (int k = 0; k < 100000; ++k) sink = sink + k;
    const double lap = watch.Lap();
    EXPECT_GE(lap, 0.0);
    laps += lap;
  }
  EXPECT_LE(laps, watch.Seconds());
}

}  // namespace
}  // namespace candi

// candi::ParallelFor (core/parallel.h): a body that throws does not cut short the loops nested
// in the bodies running beside it.
#include "core/parallel.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>

namespace candi {
namespace {

// Waits (yielding) until `flag` is set, for at most 10 s: a pairing the scheduler did not make
// ends the wait instead of hanging the test, and the assertions hold either way.
void AwaitFlag(const std::atomic<bool>& flag) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!flag.load() && std::chrono::steady_clock::now() < until) std::this_thread::yield();
}

TEST(ParallelFor, AThrowingBodyLeavesTheLoopsNestedBesideItWhole) {
  // Body 0 throws once body 1's nested loop has begun; that loop's iterations wait for the
  // throw. With TBB's bound contexts the cancellation reached the nested loop, which returned
  // early with most of its iterations skipped.
  constexpr int kNested = 64;
  for (int round = 0; round < 3; ++round) {
    std::atomic<bool> nested_started{false}, thrown{false};
    std::atomic<int> ran{0};
    int after_nested = -1;
    tbb::task_arena arena(2);
    arena.execute([&] {
      EXPECT_THROW(ParallelFor(0, 2,
                               [&](int i) {
                                 if (i == 0) {
                                   AwaitFlag(nested_started);
                                   thrown = true;
                                   throw std::runtime_error("a sink that failed");
                                 }
                                 ParallelFor(0, kNested, [&](int) {
                                   nested_started = true;
                                   AwaitFlag(thrown);
                                   ++ran;
                                 });
                                 after_nested = ran.load();
                               }),
                   std::runtime_error);
    });
    // Body 1 ran (it released body 0's wait, or body 0's wait timed out) or was skipped; if it
    // ran, its nested loop ran whole before the code after it.
    if (after_nested >= 0) {
      EXPECT_EQ(after_nested, kNested) << "round " << round;
    }
    EXPECT_TRUE(ran.load() == 0 || ran.load() == kNested) << "round " << round;
  }
}

TEST(ParallelFor, RunsEveryIndexAndRangeOnce) {
  std::atomic<int> sum{0};
  ParallelFor(0, 1000, [&](int i) { sum += i; });
  EXPECT_EQ(sum.load(), 999 * 1000 / 2);
  std::atomic<size_t> covered{0};
  ParallelFor(tbb::blocked_range<size_t>(0, 5000, 7),
              [&](const tbb::blocked_range<size_t>& r) { covered += r.size(); });
  EXPECT_EQ(covered.load(), 5000u);
}

}  // namespace
}  // namespace candi

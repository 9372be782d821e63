// candi::ParallelFor: tbb::parallel_for with its fork-join order visible to ThreadSanitizer.
//
// libtbb.so is not instrumented, so under TSan the hand-off of a body to a worker thread and the
// wait for the workers are invisible: everything a body reads from its caller, and everything the
// caller reads from the bodies afterwards, would look like a race. Under TSan the body is wrapped
// so that those edges are stated where TBB makes them: a thread releases after it creates or
// copies the body (before TBB hands the copy on), and acquires before it copies or runs one; each
// run releases at its end, and the caller acquires those after the loop (also when a body throws). Elsewhere the wrapper is
// tbb::parallel_for itself. TBB's own bookkeeping (its task objects and ranges, in its headers)
// races the same way and is suppressed in scripts/sanitize/tsan.supp.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <atomic>
#include <cstddef>
#include <cstdint>

#include "core/progress.h"

#if defined(__SANITIZE_THREAD__)
#define CANDI_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define CANDI_TSAN 1
#endif
#endif

#ifdef CANDI_TSAN
#include <sanitizer/tsan_interface.h>
#endif

namespace candi {

namespace parallel_internal {

inline void Release(const void* mark) {
#ifdef CANDI_TSAN
  __tsan_release(const_cast<void*>(mark));
#else
  (void)mark;
#endif
}
inline void Acquire(const void* mark) {
#ifdef CANDI_TSAN
  __tsan_acquire(const_cast<void*>(mark));
#else
  (void)mark;
#endif
}

// The synchronisation object of body hand-offs (one for all loops: an address, no data).
inline char hand_off = 0;

// Calls f(mark) when it goes out of scope, also by an exception.
struct Finally {
  const char* mark;
  void (*f)(const void*);
  ~Finally() { f(mark); }
};

// A body as TBB copies and runs it. `join` is the caller's mark for this loop.
template <typename Body>
struct Wrapped {
  const Body* body;
  const char* join;
  Wrapped(const Body* b, const char* j) : body(b), join(j) { Release(&hand_off); }
  Wrapped(const Wrapped& other) : body((Acquire(&hand_off), other.body)), join(other.join) {
    Release(&hand_off);
  }
  Wrapped& operator=(const Wrapped&) = delete;
  template <typename Arg>
  void operator()(const Arg& arg) const {
    Acquire(&hand_off);
    const Finally done{join, &Release};  // also when the body throws (TBB rethrows in the caller)
    (*body)(arg);
  }
};

}  // namespace parallel_internal

// Each loop runs in a context of its own (tbb::task_group_context::isolated). A body that
// throws cancels its loop: the bodies not yet started are skipped, and the exception reaches the
// caller once the running ones end. With TBB's default, bound contexts, the cancellation would
// also reach the loops nested in those running bodies, which would return early, as if done,
// with part of their work skipped; code after them would then read what was never written
// (a COPC bucket being built when the file's sink failed read unset node ids and crashed). In
// its own context a nested loop finishes whatever happens beside it.

// Over a range (tbb::blocked_range): body(const Range& subrange).
template <typename Range, typename Body>
void ParallelFor(const Range& range, const Body& body) {
  char join = 0;
  const parallel_internal::Finally joined{&join, &parallel_internal::Acquire};
  tbb::task_group_context own(tbb::task_group_context::isolated);
  tbb::parallel_for(range, parallel_internal::Wrapped<Body>(&body, &join), own);
}

// Over indices [first, last): body(index).
template <typename Index, typename Body>
void ParallelFor(Index first, Index last, const Body& body) {
  char join = 0;
  const parallel_internal::Finally joined{&join, &parallel_internal::Acquire};
  tbb::task_group_context own(tbb::task_group_context::isolated);
  tbb::parallel_for(first, last, parallel_internal::Wrapped<Body>(&body, &join), own);
}

// body(begin, end) over [0, n) in blocks of `block` on at most `threads` workers (0 = TBB's
// default), reporting progress (done, n) after each block when `progress` is set.
template <typename Body>
void ForEachBlock(int threads, size_t n, size_t block, const ProgressCallback& progress,
                  const Body& body) {
  std::atomic<uint64_t> done{0};
  auto run = [&] {
    ParallelFor(tbb::blocked_range<size_t>(0, n, block), [&](const tbb::blocked_range<size_t>& r) {
      body(r.begin(), r.end());
      if (progress) progress(done += r.size(), n);
    });
  };
  if (threads > 0) {
    tbb::task_arena arena(threads);
    arena.execute(run);
  } else {
    run();
  }
}

}  // namespace candi

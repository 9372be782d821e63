#!/usr/bin/env bash
# `make test-asan` / `make test-tsan`: the tests built with sanitizers (GCC, -O1 -g1).
#   asan  the whole suite (every ctest test `make test` runs) with AddressSanitizer and
#         UndefinedBehaviorSanitizer in build-asan/; any report fails its test.
#   tsan  ThreadSanitizer in build-tsan/ on the multi-threaded code: the renderer's tests
#         (SPBR, streaming, archive render) and the dense stereo's (PatchMatch, fusion), with
#         2 threads; then a canary race that must be reported (scripts/sanitize/tsan.supp
#         suppresses TBB's uninstrumented internals only).
# Environment: SANITIZE_JOBS (ninja and ctest jobs, nproc), CTEST_FLAGS.
set -euo pipefail
cd "$(dirname "$0")/.."
kind=${1:?usage: scripts/sanitize.sh asan|tsan}
jobs=${SANITIZE_JOBS:-$(nproc 2>/dev/null || echo 2)}
ctest_flags=${CTEST_FLAGS:---output-on-failure}
export CANDI_THREADS=2 OMP_NUM_THREADS=2

configure() {  # build dir, sanitizers, extra cmake args...
  local dir=$1 san=$2
  shift 2
  if [[ ! -f $dir/build.ninja ]]; then
    cmake -S . -B "$dir" -G Ninja -DCMAKE_BUILD_TYPE=None -DCMAKE_C_FLAGS="-O1 -g1" \
      -DCMAKE_CXX_FLAGS="-O1 -g1" -DCANDI_SANITIZE="$san" -DCANDI_BUILD_BENCH=OFF "$@" >/dev/null
  fi
}

case $kind in
  asan)
    configure build-asan address,undefined
    cmake --build build-asan -j "$jobs"
    # halt_on_error + abort: a report ends the test with a failure. Leaks are reported too.
    # libtorch, PCL and TBB are not instrumented: container-overflow annotations would then give
    # false reports on vectors passed across the boundary, so that one check is off.
    export ASAN_OPTIONS=halt_on_error=1:abort_on_error=1:detect_leaks=1:detect_container_overflow=0:strict_string_checks=1
    export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
    export LSAN_OPTIONS=suppressions=$PWD/scripts/sanitize/lsan.supp:print_suppressions=0
    cd build-asan && ctest $ctest_flags -j "$jobs" -LE slow
    ;;
  tsan)
    configure build-tsan thread -DCANDI_BUILD_RELIEF=OFF
    cmake --build build-tsan -j "$jobs" --target candi_render_test candi_photogrammetry_test
    export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$PWD/scripts/sanitize/tsan.supp"
    ./build-tsan/render/candi_render_test --gtest_filter='Spbr*:*Stream*:*Archive*:*Splat*'
    ./build-tsan/reconstruction/photogrammetry/candi_photogrammetry_test \
      --gtest_filter='PatchMatch*:Fusion*:*Dense*-SfmDense.*'
    # The canary: a race between two loop bodies must still be reported under these suppressions
    # (needs 2 hardware threads).
    canary=build-tsan/tsan_canary.log
    ./build-tsan/render/candi_render_test --gtest_also_run_disabled_tests \
      --gtest_filter='TsanCanary.*' >"$canary" 2>&1 || true
    if grep -q "WARNING: ThreadSanitizer: data race" "$canary" && grep -q "splat_cloud_test.cc" "$canary"; then
      echo "tsan: clean; the canary race between two loop bodies was reported, as it must be"
    else
      echo "tsan: the canary race was not reported, so the suppressions hide real races ($canary)" >&2
      exit 1
    fi
    ;;
  *) echo "scripts/sanitize.sh: unknown kind '$kind' (asan or tsan)" >&2; exit 1 ;;
esac

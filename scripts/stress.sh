#!/usr/bin/env bash
# `make test-stress`: the ctest suite of `make test`, STRESS_RUNS times (default 5), while
# STRESS_HOGS CPU-bound processes (default 2, as many as this machine class has cores) compete
# for the cores. Reports every test that failed even once, with the run numbers and the log of
# its first failure; exits 1 if any did. A test whose verdict depends on timing shows up here.
#
# Usage: scripts/stress.sh [BUILD_DIR]
#   STRESS_RUNS=N      runs of the suite (default 5)
#   STRESS_HOGS=K      competing busy loops (default 2; 0 for none)
#   STRESS_TESTS=RE    only the tests matching RE (ctest -R), e.g. to repeat one test 20 times
#   STRESS_JOBS=J      ctest -j (default: the number of cores, as `make test`)
#   CTEST_EXCLUDE      as in the Makefile (default: -LE slow)
set -uo pipefail
build=${1:-build}
runs=${STRESS_RUNS:-5}
hogs=${STRESS_HOGS:-2}
jobs=${STRESS_JOBS:-$(nproc 2>/dev/null || echo 2)}
exclude=${CTEST_EXCLUDE:--LE slow}
[[ -d $build ]] || { echo "stress: no build folder $build (run make build first)" >&2; exit 2; }
[[ $runs =~ ^[1-9][0-9]*$ ]] || { echo "stress: STRESS_RUNS=$runs must be a positive integer" >&2; exit 2; }
[[ $hogs =~ ^[0-9]+$ ]] || { echo "stress: STRESS_HOGS=$hogs must be a whole number" >&2; exit 2; }

logs=$build/stress
rm -rf "$logs"
mkdir -p "$logs"

hog_pids=()
stop_hogs() {
  for p in "${hog_pids[@]}"; do kill "$p" 2>/dev/null; done
  wait 2>/dev/null
}
trap stop_hogs EXIT
trap 'exit 130' INT TERM
for ((h = 0; h < hogs; ++h)); do
  # A pure busy loop: no I/O, no memory traffic, just a competitor for a core.
  bash -c 'while :; do :; done' &
  hog_pids+=($!)
done

select=()
[[ -n ${STRESS_TESTS:-} ]] && select=(-R "$STRESS_TESTS")
declare -A failed_runs=() first_log=()
start=$(date +%s)
for ((r = 1; r <= runs; ++r)); do
  t0=$(date +%s)
  log=$logs/run$r.log
  # shellcheck disable=SC2086
  (cd "$build" && ctest --output-on-failure -j "$jobs" $exclude "${select[@]}") >"$log" 2>&1
  code=$?
  summary=$(grep -E "tests passed|No tests were found" "$log" | tail -1)
  echo "stress: run $r/$runs: ${summary:-ctest exited $code} ($(($(date +%s) - t0)) s, $hogs competing busy loops)" >&2
  if [[ $code -ne 0 ]]; then
    mapfile -t names < <(sed -n 's/^[0-9]*:\(.*\)$/\1/p' "$build/Testing/Temporary/LastTestsFailed.log" 2>/dev/null)
    [[ ${#names[@]} -eq 0 && -z $summary ]] && names=("(ctest itself: exit $code, see $log)")
    for n in "${names[@]}"; do
      failed_runs[$n]="${failed_runs[$n]:-}${failed_runs[$n]:+,}$r"
      [[ -n ${first_log[$n]:-} ]] || first_log[$n]=$log
    done
  fi
done

echo "stress: $runs run(s) in $(($(date +%s) - start)) s with $hogs competing busy loops; logs in $logs/" >&2
if [[ ${#failed_runs[@]} -eq 0 ]]; then
  echo "stress: no test failed in any run" >&2
  exit 0
fi
echo "stress: ${#failed_runs[@]} test(s) failed at least once:" >&2
for n in "${!failed_runs[@]}"; do
  count=$(tr ',' '\n' <<<"${failed_runs[$n]}" | wc -l)
  echo "  $n: failed $count of $runs (runs ${failed_runs[$n]}; first log ${first_log[$n]})" >&2
done
exit 1

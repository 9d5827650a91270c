#!/usr/bin/env bash
# test_bench_smoke.sh — every scripts/bench-* in a smoke mode (issue 32.4): tiny sizes, few frames, one round, against
# the test build (TASLAB_BUILD) and a private results folder (TASLAB_BENCH_RUNS), with the Khronos validation layer
# on. No time is asserted — the figures mean nothing at these sizes; what fails is a benchmark that no longer runs
# (exit status) or no longer prints its table (the line checked per benchmark below), so a change that breaks one
# fails CI instead of rotting until someone measures again.
# Usage: test_bench_smoke.sh BUILD_DIR WORK_DIR [BENCH...]     (default: every benchmark)
set -euo pipefail
build="$(cd "$1" && pwd)" work="$2"
shift 2
cd "$(dirname "$0")/.."
source tests/require.sh
# Leak checking is the other tests' job: the benchmarks' helper programs (bench_methods, bench_scene_load) do not
# pin the Vulkan driver as taslab processes do (tests/lsan_env.sh), so its unloaded state would show as leaks.
export ASAN_OPTIONS=detect_leaks=0:quarantine_size_mb=8
export TASLAB_BUILD="$build" TASLAB_BENCH_RUNS="$work" TASLAB_VALIDATION=1
rm -rf "$work" && mkdir -p "$work"
# name | arguments | a line its output must have
smokes=(
  "bench-render|--frames 2 --sizes 64x36|64x36 *[0-9]"
  "bench-scenes|--blocks 1 --block-frames 2 --size 64x36|^calm "
  "bench-clip|--frames 2 --size 64x36|clip encode:"
  "bench-tfr|--frames 2 --size 64x36 --no-analysis|tfr"
  "bench-methods|--size 64x36 --frames 0:3 --paths calm:walk|calm / walk"
  "bench-methods|--set table1 --size 64x36 --frames 0:3 --paths calm:walk|calm / walk"
  "bench-methods|--set vrs --size 64x36 --frames 0:3 --paths calm:fan_shadow|calm / fan_shadow"
  "bench-methods|--set stereo --size 32x18 --frames 0:2 --paths calm:walk|calm / walk"
  "bench-methods|--set alt --size 64x36 --frames 0:3 --paths dynamic:deck|dynamic / deck"
  "bench-methods|--set atlas --size 64x36 --frames 0:3 --paths moderate:boulders|moderate / boulders"
  "bench-methods|--set oracle --size 64x36 --frames 0:3 --paths calm:fan_shadow|calm / fan_shadow"
  "bench-methods|--set payload --size 64x36 --frames 0:3 --paths calm:fan_shadow|calm / fan_shadow"
  "bench-ab|--old same --size 64x36 --frames 0:3 --first 1 --rounds 1 --paths dynamic:deck|dynamic / deck | stu4 | new | 1 |"
  "bench-metrics|--pairs 2 --runs 1 --compute-runs 1|metrics speed"
  "bench-sweep|--frames 0:2 --size 64x36 --variants ref,tfr@8|resume after SIGKILL"
  "bench-study|--participants 3|: 60 test ratings in the database (expected 60)"
  "bench-study|--participants 3 --client node --addresses many|the server's time per answer p50"
  "bench-study|--participants 3 --think-ms 100 --poll-status|status page: [1-9][0-9]* replies while the participants answered, taking"
  "bench-thresholds|--studies 2|sd 1: .*RMSE"
)
failed=0
for s in "${smokes[@]}"; do
  IFS='|' read -r name args want <<<"$s"
  if [ $# -gt 0 ] && [[ " $* " != *" $name "* ]]; then continue; fi
  log="$work/$name-$(echo "$args" | tr -c 'a-z0-9' _).log"
  t0=$(date +%s)
  # shellcheck disable=SC2086
  if ! scripts/$name $args >"$log" 2>&1; then
    echo "FAIL: scripts/$name $args exited non-zero; its output:"; tail -30 "$log"; failed=1; continue
  fi
  if ! grep -q "$want" "$log"; then
    echo "FAIL: scripts/$name $args printed no line with '$want'; its output:"; tail -30 "$log"; failed=1; continue
  fi
  echo "ok: scripts/$name $args ($(( $(date +%s) - t0 )) s)"
done
exit $failed

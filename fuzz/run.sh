#!/usr/bin/env bash
# Runs fuzz targets for SECONDS each from their seed corpora; exits non-zero on the first target
# that finds a crash, leak or sanitizer report (the input is left in BUILD/fuzz/findings/TARGET/,
# the whole output in BUILD/fuzz/TARGET.log). Past findings in fuzz/regressions/ are replayed first.
# Usage: fuzz/run.sh BUILD_DIR SECONDS [TARGET...]   (targets: core_map mrpt_archive ini insert)
# Extra libFuzzer flags may come in RTOG_FUZZ_FLAGS (e.g. -runs=10000000).
set -euo pipefail
build=$1 secs=$2
shift 2
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=(core_map mrpt_archive ini insert)
src=$(cd "$(dirname "$0")" && pwd)
export ASAN_SYMBOLIZER_PATH=${ASAN_SYMBOLIZER_PATH:-/usr/lib/llvm-14/bin/llvm-symbolizer}
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
for t in "${targets[@]}"; do
  corpus=$build/fuzz/corpus/$t findings=$build/fuzz/findings/$t log=$build/fuzz/$t.log
  mkdir -p "$corpus" "$findings"
  seeds=()
  for d in "$build/fuzz/seeds/$t" "$src/corpus/$t"; do
    if [ -d "$d" ]; then seeds+=("$d"); fi
  done
  # The inputs of past findings (fuzz/regressions/TARGET-*.bin) first, each run once: a fix that
  # comes undone fails here, whatever the random run below finds.
  regressions=("$src"/regressions/"$t"-*.bin)
  if [ -e "${regressions[0]}" ]; then
    echo "=== rtog_fuzz_$t: ${#regressions[@]} past findings"
    "$build/fuzz/rtog_fuzz_$t" "${regressions[@]}" > "$log.regressions" 2>&1 || {
      tail -n 60 "$log.regressions"
      echo "rtog_fuzz_$t: a past finding fails again (see $log.regressions)"
      exit 1
    }
  fi
  echo "=== rtog_fuzz_$t: ${secs} s, corpus $corpus, seeds ${seeds[*]:-none}"
  rc=0
  # shellcheck disable=SC2086
  "$build/fuzz/rtog_fuzz_$t" -max_total_time="$secs" -print_final_stats=1 -artifact_prefix="$findings/" \
    -seed=${RTOG_FUZZ_SEED:-1} -timeout=10 -rss_limit_mb=2048 ${RTOG_FUZZ_FLAGS:-} "$corpus" "${seeds[@]}" > "$log" 2>&1 || rc=$?
  grep -E "^#[0-9]+ +(DONE|INITED)|^stat::|ERROR|SUMMARY|Test unit written" "$log" | tail -n 20 || true
  if [ "$rc" -ne 0 ]; then
    tail -n 60 "$log"
    echo "rtog_fuzz_$t found a problem (exit $rc): see $findings/ and $log"
    exit 1
  fi
done

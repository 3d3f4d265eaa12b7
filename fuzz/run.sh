#!/usr/bin/env bash
# Runs fuzz targets for SECONDS each from their kept corpora (fuzz/corpus/TARGET, in the
# repository), the generated seeds (BUILD/fuzz/seeds/TARGET) and what earlier runs in this build
# found (BUILD/fuzz/corpus/TARGET, where new inputs go); exits non-zero on the first target that
# finds a crash, leak or sanitizer report (the input is left in BUILD/fuzz/findings/TARGET/, the
# whole output in BUILD/fuzz/TARGET.log). Before each run, the past findings in fuzz/regressions/
# are replayed and the kept corpus is checked against its budget (fuzz/targets.sh). After it, the
# new inputs that add coverage are merged into a copy of the kept corpus (BUILD/fuzz/merged/TARGET)
# and one line gives its files, bytes, cov:/ft: and the run's executions; `fuzz/merge_corpus.sh
# BUILD` merges them into fuzz/corpus itself, to be committed.
# Usage: fuzz/run.sh BUILD_DIR SECONDS [TARGET...]   (targets: core_map mrpt_archive ini insert)
# libFuzzer's seed is RTOG_FUZZ_SEED (default 0: a new one each run, printed, so that runs from an
# unchanged corpus do not repeat each other). Extra libFuzzer flags may come in RTOG_FUZZ_FLAGS.
set -euo pipefail
build=$1 secs=$2
shift 2
targets=("$@")
src=$(cd "$(dirname "$0")" && pwd)
# shellcheck source=targets.sh
. "$src/targets.sh"
[ ${#targets[@]} -gt 0 ] || targets=("${RTOG_FUZZ_ALL_TARGETS[@]}")
for t in "${targets[@]}"; do
  len=${RTOG_FUZZ_MAX_LEN[$t]:?unknown target $t}
  kept=$src/corpus/$t corpus=$build/fuzz/corpus/$t findings=$build/fuzz/findings/$t log=$build/fuzz/$t.log
  mkdir -p "$corpus" "$findings"
  read -r files bytes big < <(corpus_size "$kept" "$len")
  if [ "$bytes" -gt "$RTOG_FUZZ_CORPUS_BUDGET" ] || [ "$big" -gt 0 ]; then
    echo "fuzz/corpus/$t: $files files, $bytes bytes, $big over $len bytes: over its budget of"
    echo "$RTOG_FUZZ_CORPUS_BUDGET bytes in files of at most $len (fuzz/targets.sh). Remove the larger"
    echo "files, re-minimize it (fuzz/merge_corpus.sh --minimize BUILD $t) or raise the budget on purpose."
    exit 1
  fi
  dirs=("$corpus")
  for d in "$kept" "$build/fuzz/seeds/$t"; do
    if [ -d "$d" ]; then dirs+=("$d"); fi
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
  echo "=== rtog_fuzz_$t: ${secs} s, -max_len=$len, corpora ${dirs[*]}"
  rc=0
  # shellcheck disable=SC2086
  "$build/fuzz/rtog_fuzz_$t" -max_total_time="$secs" -print_final_stats=1 -artifact_prefix="$findings/" \
    -seed="${RTOG_FUZZ_SEED:-0}" -max_len="$len" -timeout=10 -rss_limit_mb=2048 ${RTOG_FUZZ_FLAGS:-} \
    "${dirs[@]}" > "$log" 2>&1 || rc=$?
  grep -E "^INFO: Seed:|^#[0-9]+[[:space:]]+(DONE|INITED)|^stat::|ERROR|SUMMARY|Test unit written" "$log" | tail -n 20 || true
  if [ "$rc" -ne 0 ]; then
    tail -n 60 "$log"
    echo "rtog_fuzz_$t found a problem (exit $rc): see $findings/ and $log"
    exit 1
  fi
  bash "$src/merge_corpus.sh" --out "$build/fuzz/merged" "$build" "$t" || true
done

#!/usr/bin/env bash
# Keeps what fuzzing found: merges into each target's kept corpus, fuzz/corpus/TARGET, the inputs of
# the last run (BUILD/fuzz/corpus/TARGET) and the generated seeds (BUILD/fuzz/seeds/TARGET) that add
# coverage, with libFuzzer's -merge=1 (an input is taken only if it adds features to those of the
# kept corpus and of the inputs taken before it, smallest first). Commit fuzz/corpus with the change.
# Then prints one line per target, the figures doc/reliability.md gives:
#   corpus TARGET: F files, B bytes; cov: C ft: T; added N files (M new features, E new edges);
#   executions X
# cov:/ft: are libFuzzer's counts of edges and features on loading the kept corpus (-runs=0);
# executions are stat::number_of_executed_units of the last run (BUILD/fuzz/TARGET.log).
# Usage: fuzz/merge_corpus.sh [--minimize] [--out DIR] BUILD_DIR [TARGET...]
#   --minimize  rebuild the corpus from itself, the run's inputs and the seeds: inputs whose
#               features the others cover are dropped (fewer bytes; a larger diff to commit)
#   --out DIR   merge into DIR/TARGET, a copy of the kept corpus, and leave fuzz/corpus alone
#               (what fuzz/run.sh, and so CI, does after each run)
# Exits non-zero if a merged corpus is over its budget (fuzz/targets.sh).
set -euo pipefail
src=$(cd "$(dirname "$0")" && pwd)
# shellcheck source=targets.sh
. "$src/targets.sh"
minimize=0 out=
while [ $# -gt 0 ]; do
  case $1 in
    --minimize) minimize=1; shift ;;
    --out) out=$2; shift 2 ;;
    *) break ;;
  esac
done
[ $# -ge 1 ] || { echo "usage: $0 [--minimize] [--out DIR] BUILD_DIR [TARGET...]" >&2; exit 2; }
build=$1
shift
targets=("$@")
[ ${#targets[@]} -gt 0 ] || targets=("${RTOG_FUZZ_ALL_TARGETS[@]}")
status=0
for t in "${targets[@]}"; do
  len=${RTOG_FUZZ_MAX_LEN[$t]:?unknown target $t}
  bin=$build/fuzz/rtog_fuzz_$t log=$build/fuzz/$t
  flags=(-max_len="$len" -timeout=10 -rss_limit_mb=2048)
  kept=$src/corpus/$t
  mkdir -p "$kept"
  dest=$kept
  if [ -n "$out" ]; then
    dest=$out/$t
    rm -rf "$dest"
    mkdir -p "$dest"
    cp -rp "$kept/." "$dest/"
  fi
  read -r files0 bytes0 _ < <(corpus_size "$dest" "$len")
  sources=()
  for d in "$build/fuzz/corpus/$t" "$build/fuzz/seeds/$t"; do
    if [ -d "$d" ]; then sources+=("$d"); fi
  done
  added="added 0 files (0 new features, 0 new edges)"
  if [ "$minimize" = 1 ]; then
    fresh=$(mktemp -d)
    "$bin" -merge=1 "${flags[@]}" "$fresh" "$dest" "${sources[@]}" > "$log.merge.log" 2>&1 || {
      tail -n 30 "$log.merge.log"; echo "merge of $t failed (see $log.merge.log)"; exit 1; }
    find "$dest" -maxdepth 1 -type f -delete
    cp -rp "$fresh/." "$dest/"
    rm -rf "$fresh"
    added="minimized from $files0 files, $bytes0 bytes"
  elif [ ${#sources[@]} -gt 0 ]; then
    "$bin" -merge=1 "${flags[@]}" "$dest" "${sources[@]}" > "$log.merge.log" 2>&1 || {
      tail -n 30 "$log.merge.log"; echo "merge of $t failed (see $log.merge.log)"; exit 1; }
    # "MERGE-OUTER: 3 new files with 12 new features added; 2 new coverage edges"
    added=$(sed -n 's/^MERGE-OUTER: \([0-9]*\) new files with \([0-9]*\) new features added; \([0-9]*\) new coverage edges.*/added \1 files (\2 new features, \3 new edges)/p' \
      "$log.merge.log" | tail -n 1)
  fi
  "$bin" -runs=0 "${flags[@]}" "$dest" > "$log.stats.log" 2>&1 || {
    tail -n 30 "$log.stats.log"; echo "loading the corpus of $t failed (see $log.stats.log)"; exit 1; }
  cov=$(sed -n 's/^#[0-9]*[[:space:]]*INITED \(cov: [0-9]* ft: [0-9]*\).*/\1/p' "$log.stats.log" | tail -n 1)
  execs=
  if [ -f "$log.log" ]; then execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log.log" | tail -n 1); fi
  read -r files bytes big < <(corpus_size "$dest" "$len")
  echo "corpus $t: $files files, $bytes bytes ($dest); ${cov:-cov: ? ft: ?}; ${added:-added ?}; executions ${execs:-none} (last run)"
  if [ "$bytes" -gt "$RTOG_FUZZ_CORPUS_BUDGET" ] || [ "$big" -gt 0 ]; then
    echo "corpus $t is over its budget ($RTOG_FUZZ_CORPUS_BUDGET bytes, files of at most $len bytes; $big larger): $0 --minimize"
    status=1
  fi
done
exit $status

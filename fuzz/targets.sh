# shellcheck shell=bash
# Sourced by fuzz/run.sh and fuzz/merge_corpus.sh: the targets, and the bounds of the corpora kept
# in the repository (fuzz/corpus/TARGET, so that each run starts where the last one ended).
# RTOG_FUZZ_MAX_LEN is libFuzzer's -max_len for every run and merge of a target, and so the
# largest file its corpus can hold. Each holds the target's generated seeds whole (the TUM map
# seeds are up to 37 KiB, the archives of three SENA scans up to 19 KiB, share/rtog/config's .ini
# files up to 6 KiB); the insertion target has no seeds, and 1 KiB holds two full observations.
# shellcheck disable=SC2034
RTOG_FUZZ_ALL_TARGETS=(core_map mrpt_archive ini insert)
declare -A RTOG_FUZZ_MAX_LEN=([core_map]=65536 [mrpt_archive]=65536 [ini]=8192 [insert]=1024)
# A kept corpus larger than this fails fuzz/run.sh (and so CI): re-minimize it
# (fuzz/merge_corpus.sh --minimize) rather than let the repository grow.
RTOG_FUZZ_CORPUS_BUDGET=$((2 * 1024 * 1024))
export ASAN_SYMBOLIZER_PATH=${ASAN_SYMBOLIZER_PATH:-/usr/lib/llvm-14/bin/llvm-symbolizer}
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

# corpus_size DIR LEN: "FILES BYTES LARGER" of the files directly in DIR, LARGER those over LEN
# bytes (0 0 0 if DIR does not exist).
corpus_size() {
  if [ -d "$1" ]; then
    find "$1" -maxdepth 1 -type f -printf '%s\n' |
      awk -v len="$2" '{n++; b+=$1; if ($1 > len) big++} END {printf "%d %d %d\n", n, b, big}'
  else
    echo "0 0 0"
  fi
}

#!/usr/bin/env bash
# Grows the fuzz targets' working corpora by fuzzing, and minimises them into the small corpus
# checked in under fuzz/corpus/TARGET/ (fuzz/README.md). Run from the repository root:
#
#   fuzz/regenerate-corpus.sh build               the targets, as `cargo fuzz build` does
#   fuzz/regenerate-corpus.sh grow [SECONDS]      each target fuzzed SECONDS (default 600) in turn,
#                                                 seeded from fuzz/corpus/TARGET, new inputs kept in
#                                                 $WORK/TARGET: the larger corpus
#   fuzz/regenerate-corpus.sh minimise            fuzz/corpus/TARGET rewritten: its named seeds,
#                                                 then the fewest inputs of fuzz/corpus/TARGET and
#                                                 $WORK/TARGET that reach every edge they reach
#
# TARGETS (default: every target in fuzz/fuzz_targets/) picks targets; WORK defaults to
# /tmp/fragsim-fuzz. Needs the nightly toolchain and cargo-fuzz (`cargo install cargo-fuzz`).
#
# Minimising is libFuzzer's `-set_cover_merge=1` (a greedy set cover: the input reaching the most
# edges not yet reached first) over edges alone (`-use_counters=0`): `cargo fuzz cmin` merges over
# edges and hit-count buckets with `-merge=1`, which keeps about three times the files. Files not
# named by their SHA-1 (hand-made seeds, regressions such as `regression-*`) and the regressions
# listed in KEEP below stay whatever their coverage, and are merged first, so that nothing they
# reach is paid for twice.
set -euo pipefail

WORK=$(realpath -m "${WORK:-/tmp/fragsim-fuzz}")
TARGET_DIR=$(realpath -m "${CARGO_TARGET_DIR:-fuzz/target}")
BIN=$TARGET_DIR/x86_64-unknown-linux-gnu/release
ROOT=$PWD
TARGETS=${TARGETS:-$(basename -s .rs fuzz/fuzz_targets/*.rs)}
# Inputs named by their SHA-1 that are regressions of past bugs (the fix commit names them).
KEEP=(
  dump_layouts/01bb91ef0f97c4e9b211b0fbe6766627c99676e1 # pages: a read past an array with no page
)
# Every input gets at most 10 s and 2 GiB (a hang or a runaway allocation is a crash); stdout is
# closed, since `compare` prints the command's report for each pair of dumps that decode.
LIMITS=(-timeout=10 -rss_limit_mb=2048 -close_fd_mask=1)

build() {
  cargo +nightly fuzz build --sanitizer none --release --debug-assertions --target-dir "$TARGET_DIR"
}

grow() {
  local seconds=${1:-600}
  for target in $TARGETS; do
    mkdir -p "$WORK/$target/run" "$WORK/$target/corpus"
    (cd "$WORK/$target/run" && "$BIN/$target" "${LIMITS[@]}" \
      -max_total_time="$seconds" -print_final_stats=1 -artifact_prefix="$WORK/$target/run/" \
      "$WORK/$target/corpus" "$ROOT/fuzz/corpus/$target")
    echo "$target: $(ls "$WORK/$target/corpus" | wc -l) new inputs in $WORK/$target/corpus"
  done
}

minimise() {
  for target in $TARGETS; do
    local checked_in=fuzz/corpus/$target fresh=$WORK/$target/minimised
    rm -rf "$fresh"
    mkdir -p "$fresh" "$WORK/$target/corpus"
    # The named seeds and the listed regressions first: they stay.
    find "$checked_in" -type f -regextype posix-extended ! -regex '.*/[0-9a-f]{40}' -exec cp {} "$fresh/" \;
    for kept in "${KEEP[@]}"; do
      if [[ $kept == "$target"/* && -f fuzz/corpus/$kept ]]; then cp "fuzz/corpus/$kept" "$fresh/"; fi
    done
    "$BIN/$target" "${LIMITS[@]}" -set_cover_merge=1 -use_counters=0 \
      "$fresh" "$checked_in" "$WORK/$target/corpus" > "$WORK/$target/minimise.log" 2>&1
    rm -rf "$checked_in"
    mv "$fresh" "$checked_in"
    echo "$target: $(ls "$checked_in" | wc -l) files, $(du -sh "$checked_in" | cut -f1)"
  done
}

case ${1:-} in
  build) build ;;
  grow) grow "${2:-600}" ;;
  minimise) minimise ;;
  *) sed -n '2,14p' "$0" >&2; exit 2 ;;
esac

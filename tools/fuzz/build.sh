#!/usr/bin/env bash
# Builds every fuzz target as cargo-fuzz would with `--sanitizer none` (libFuzzer's coverage
# instrumentation, `--cfg fuzzing`, debug assertions and overflow checks), without cargo-fuzz
# itself: nightly Rust is enough. The binaries land in fuzzbin/ (stripped), ready to carry to a
# machine without cargo (tools/device/fuzz.sh).
set -eu
export CARGO_TARGET_DIR=${CARGO_TARGET_DIR:-target/fuzz}
export RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing -Cdebug-assertions -Coverflow_checks"
cargo +nightly build --release --manifest-path fuzz/Cargo.toml --target x86_64-unknown-linux-gnu --bins
mkdir -p fuzzbin
for target in fuzz/fuzz_targets/*.rs; do
  name=$(basename "$target" .rs)
  strip -o "fuzzbin/$name" "$CARGO_TARGET_DIR/x86_64-unknown-linux-gnu/release/$name"
done
ls -la fuzzbin

#!/usr/bin/env bash
# Long fuzz runs on a many-core machine without cargo (the H200 machine; docs/results.md,
# "Fuzzing"): the targets are built here with nightly Rust and cargo-fuzz's flags
# (tools/fuzz/build.sh) and carried as `fuzzbin/`. Each target gets WORKERS libFuzzer processes
# (`-jobs`) sharing one working corpus, seeded from the checked-in `fuzz/corpus/TARGET`, for
# SECONDS_EACH seconds of wall time; then its working corpus is minimised (`-merge=1`). The
# workers' logs, any crash and the minimised corpora come back as one archive, $OUT/fuzz.tgz.
# Every input gets at most 10 s and 2 GiB (`-timeout`, `-rss_limit_mb`: a hang or a runaway
# allocation is a crash); stdout is closed (`-close_fd_mask=1`), since `compare` prints the
# command's report for each pair of dumps that decode. MERGE=0 skips the minimising (a run that
# only looks for crashes within a time budget).
set -u
SECONDS_EACH=${SECONDS_EACH:-540}
WORKERS=${WORKERS:-4}
MERGE=${MERGE:-1}
OUT=${OUT:-/tmp/fuzz-out}
root=$PWD
mkdir -p "$OUT" /tmp/fz
for bin in fuzzbin/*; do
  target=$(basename "$bin")
  mkdir -p /tmp/fz/$target/run /tmp/fz/$target/corpus /tmp/fz/$target/min
  cp fuzz/corpus/"$target"/* /tmp/fz/$target/corpus/ 2>/dev/null
  (cd /tmp/fz/$target/run && "$root/$bin" -jobs="$WORKERS" -workers="$WORKERS" \
      -max_total_time="$SECONDS_EACH" -print_final_stats=1 \
      -timeout=10 -rss_limit_mb=2048 -close_fd_mask=1 -artifact_prefix=/tmp/fz/$target/run/ \
      /tmp/fz/$target/corpus > driver.log 2>&1) &
done
wait
for bin in fuzzbin/*; do
  target=$(basename "$bin")
  if [ "$MERGE" = 1 ]; then
    "$bin" -merge=1 -close_fd_mask=1 /tmp/fz/$target/min /tmp/fz/$target/corpus > /tmp/fz/$target/merge.log 2>&1
  fi
  echo "$target: $(ls /tmp/fz/$target/corpus | wc -l) working, $(ls /tmp/fz/$target/min | wc -l) minimised"
  grep -h "stat::number_of_executed_units\|stat::peak_rss" /tmp/fz/$target/run/fuzz-*.log
  grep -l "SUMMARY\|panicked\|deadly signal" /tmp/fz/$target/run/fuzz-*.log
done
tar -C /tmp/fz --exclude='*/corpus' -czf "$OUT/fuzz.tgz" .
ls -la "$OUT"

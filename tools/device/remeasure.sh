#!/usr/bin/env bash
# The re-measurement of issue 14 (trust): every figure of docs/results.md and docs/baselines/*.md
# that the trust changes move (fixed-capacity A-buffer, counting passes, overflow predicted by
# the oracle, k-buffer write-back models), on the device machine's 16 cores.
# Usage (device): tools/device/remeasure.sh FRAGSIM DRAGON OUTDIR
set -euo pipefail
B=$1 D=$2 R=$3
mkdir -p "$R" /tmp/remeasure
cd /tmp/remeasure
lscpu | grep -E "Model name|^CPU\(s\)" > "$R/machine.txt"
"$B" --scheme all --executor all --json --no-images > "$R/all-bunny.json"
"$B" --scheme all --executor all --k auto --capacity auto --json --no-images > "$R/all-bunny-auto.json"
"$B" --mesh "$D" --scheme all --executor all --json --no-images > "$R/all-dragon.json"
"$B" --scheme abuffer,abuffer-exact,mdts --json --no-images > "$R/done-abuffer.json"
"$B" --scene bunny-spheres --scheme abuffer,abuffer-exact --capacity 8 --json --no-images > "$R/bunny-spheres-abuffer8.json" || true
for K in 1 2 4 8 16; do
  for M in bunny dragon; do
    if [ $M = bunny ]; then S=(--scene bunny); else S=(--mesh "$D"); fi
    "$B" bench "${S[@]}" --k $K --capacity auto --frames 1 --scheme mdts,loop32,layer-counter,linked-list,linked-list-nearest \
      --json --out "ship-$M-$K" > "$R/ship-$M-$K.json"
  done
done
"$B" bench --frames 5 --json --out bench-bunny > "$R/bench-bunny.json"
"$B" bench --mesh "$D" --frames 5 --json --out bench-dragon > "$R/bench-dragon.json"
"$B" bench --scene bunny-spheres --frames 3 --json --out bench-bunny-spheres > "$R/bench-bunny-spheres.json"
[ "${SWEEP:-0}" = 1 ] && "$B" sweep --scene bunny-spheres --width 256 --height 256 \
  --scheme bdp,bdp-single,bdp2,adp,kbuffer,mdts-packed,mdts,abuffer --out sweep-bunny-spheres > /dev/null
[ "${SWEEP:-0}" = 1 ] && cp sweep-bunny-spheres/sweep.json "$R/sweep-bunny-spheres.json"
true

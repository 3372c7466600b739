#!/bin/bash
# A/B on the device: fragsim-A (before) against fragsim (after), 16 threads, interleaved rounds.
D=target/devbin
for round in 1 2 3; do
  for b in fragsim-A fragsim; do
    for mesh in dragon_vrip.ply.gz stanford-bunny.obj; do
      $D/$b bench --mesh $D/$mesh --scheme mdts --scheme abuffer --executor parallel --threads 16 \
        --frames 60 --out /tmp/ab 2>&1 | grep -E "^\| (mdts|abuffer)" | \
        awk -F'|' -v n="$round $b ${mesh%%.*}" '{print n, $2, "v", $15, "p", $16, "post", $17, "frame", $18, "min", $19}'
    done
  done
done

#!/bin/bash
# Scaling run on the device: thread counts, both meshes, MDTS (plain and probing) and the
# A-buffer on the parallel and tiled executors (serial once, at 1 thread).
# BIN (binary under target/devbin), THREADS, FRAMES, TAG; results under /tmp/results.
set -u
D=target/devbin
R=/tmp/results
mkdir -p $R
BIN=${BIN:-fragsim}
TAG=${TAG:-$BIN}
FRAMES=${FRAMES:-40}
THREADS=${THREADS:-"1 2 4 8 16"}
(date -u; lscpu; free -g) > $R/machine.txt
for mesh in ${MESHES:-dragon_vrip.ply.gz stanford-bunny.obj}; do
  for t in $THREADS; do
    if [ "$t" = 1 ]; then execs="serial parallel tiled"; else execs="parallel tiled"; fi
    for ex in $execs; do
      name=$TAG-${mesh%%.*}-t$t-$ex
      $D/$BIN bench --mesh $D/$mesh --scheme mdts --scheme mdts-probe --scheme abuffer \
        --executor $ex --threads $t --frames $FRAMES --out $R/$name > $R/$name.md 2>&1
      grep -E "^\| (mdts|abuffer)" $R/$name.md | awk -F'|' -v n=$name '{print n, $2, "lost", $10, "mism", $11, "lk", $14, "v", $15, "p", $16, "r", $17, "frame", $18, "min", $19, "fps", $21}'
    done
  done
done

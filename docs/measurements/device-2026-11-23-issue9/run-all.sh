#!/bin/bash
D=target/devbin
# A/B first: the binaries one after another, twice, dragon at 16 threads, tiled executor.
for round in 1 2; do
  for b in fragsim-A fragsim fragsim-v3; do
    [ -x $D/$b ] && BIN=$b TAG=ab$round-$b THREADS=16 MESHES=dragon_vrip.ply.gz FRAMES=60 bash $D/scaling.sh
  done
done
BIN=fragsim TAG=final FRAMES=60 bash $D/scaling.sh
[ -x $D/fragsim-v3 ] && BIN=fragsim-v3 TAG=v3 THREADS="8 16" FRAMES=60 bash $D/scaling.sh
tar czf $OUT/results.tgz -C /tmp results

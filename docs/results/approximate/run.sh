#!/bin/bash
# The figures of docs/results.md "Approximate OIT against the exact answer" and the
# per-depth-complexity tables of docs/journal/2026-12-02-approximate-oit.md: bench at K = 8 and
# 4 on the bunny, the dragon and bunny-spheres, at K = 2, 16 and 32 on bunny-spheres, and sweep on the bunny and bunny-spheres
# (the dragon too with SWEEP_DRAGON=1), all at 512². Each run's bench.md / sweep table and its
# JSON Lines are kept as $O/<run>.md (.txt) and $O/<run>.jsonl; `python3 tables.py $O` prints
# the tables from the JSON Lines.
set -e
B=${FRAGSIM:-target/release/fragsim}
D=${DRAGON:-../shared/meshes/dragon_vrip.ply.gz}
O=${OUT:-out/approximate}
SIZE=(--width 512 --height 512)
mkdir -p "$O"
scene_args() { if [ "$1" = dragon ]; then echo "--mesh $D"; else echo "--scene $1"; fi; }

# bench SCENE K CATALOG_SCHEMES
bench() {
  /usr/bin/time -f "$1 k$2 %e s" $B bench $(scene_args $1) "${SIZE[@]}" --frames 3 \
    --scheme $3 --approximate wboit,mlab,tail-blend --k $2 --out $O/$1-k$2 > $O/$1-k$2.md
  cp $O/$1-k$2/bench.jsonl $O/$1-k$2.jsonl
}
for scene in bunny dragon bunny-spheres; do
  bench $scene 8 mdts,bdp,adp,mdts-packed,mlab
  bench $scene 4 mdts
done
for k in 2 16 32; do bench bunny-spheres $k mdts; done

# sweep SCENE: 8 angles, K = 8, beside MDTS and BDP.
sweep() {
  /usr/bin/time -f "$1 sweep %e s" $B sweep $(scene_args $1) "${SIZE[@]}" --angles 8 \
    --scheme mdts,bdp --approximate wboit,mlab,tail-blend --k 8 --out $O/$1-sweep > $O/$1-sweep.txt
  cp $O/$1-sweep/sweep.jsonl $O/$1-sweep.jsonl
}
sweep bunny
sweep bunny-spheres
if [ -n "$SWEEP_DRAGON" ]; then sweep dragon; fi

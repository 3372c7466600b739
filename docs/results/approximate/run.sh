#!/bin/bash
# The figures of docs/results.md "Approximate OIT against the exact answer (issue 19)".
set -e
B=${FRAGSIM:-target/release/fragsim}
D=${DRAGON:-../shared/meshes/dragon_vrip.ply.gz}
O=${OUT:-out/approximate}
mkdir -p "$O"
for scene in bunny dragon bunny-spheres; do
  case $scene in
    dragon) S=(--mesh $D) ;;
    *) S=(--scene $scene) ;;
  esac
  for k in 8 4; do
    if [ $k = 8 ]; then C=mdts,bdp,adp,mdts-packed,mlab; else C=zbuffer; fi
    /usr/bin/time -f "$scene k$k %e s" $B bench "${S[@]}" --width 512 --height 512 --frames 3 \
      --scheme $C --approximate wboit,mlab,tail-blend --k $k --out $O/$scene-k$k > $O/$scene-k$k.md
  done
done

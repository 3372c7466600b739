#!/usr/bin/env bash
# Two fragsim binaries alternated in one call on the device, for the frame-time table of the
# speed work: each row (scene, viewport, executor, threads) runs BASE then NEW, or NEW then BASE
# on alternate rows, `bench --frames FRAMES` each (the median of those frames is `time_ms`), MDTS
# and the fixed A-buffer. Prints one line per row and scheme: both medians, their ratio, and each
# binary's vertex, passes and resolve medians, lost and mismatched (both must be 0).
#
#   BASE=./fragsim-base NEW=./fragsim-new MESH=./dragon_vrip.ply.gz tools/device/ab-frames.sh
#
# Environment (defaults in brackets): BASE, NEW (required); MESH [dragon_vrip.ply.gz beside the
# script]; FRAMES [20]; ROWS: the rows, `scene:side:executor:threads` separated by spaces, scene
# `dragon` or `bunny-spheres` [the issue's rows]; BUDGET [480] seconds, after which rows are
# skipped and named; OUT [/tmp/ab-frames]. Not a test: nothing in cargo test or CI runs it.
set -euo pipefail

here=$(cd "$(dirname "$0")" && pwd)
: "${BASE:?set BASE}" "${NEW:?set NEW}"
MESH=${MESH:-$here/dragon_vrip.ply.gz}
FRAMES=${FRAMES:-20}
BUDGET=${BUDGET:-480}
OUT=${OUT:-/tmp/ab-frames}
ROWS=${ROWS:-dragon:512:parallel:16 dragon:512:tiled:16 dragon:2048:parallel:16 dragon:2048:tiled:16 bunny-spheres:512:parallel:16 bunny-spheres:512:tiled:16 dragon:512:parallel:1 dragon:512:tiled:1}
mkdir -p "$OUT"
echo "== $(date -u '+%Y-%m-%d %H:%M:%S UTC'), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "== bench --scheme mdts,abuffer --frames $FRAMES --no-images; BASE $BASE, NEW $NEW"
row=0
for spec in $ROWS; do
    IFS=: read -r scene side executor threads <<< "$spec"
    if [ "$SECONDS" -ge "$BUDGET" ]; then
        echo "== skipped (budget): $spec"
        continue
    fi
    case $scene in
        dragon) args=(--mesh "$MESH") ;;
        *) args=(--scene "$scene") ;;
    esac
    order=(BASE NEW)
    [ $((row % 2)) -eq 1 ] && order=(NEW BASE)
    for which in "${order[@]}"; do
        binary=${!which}
        "$binary" bench "${args[@]}" --width "$side" --height "$side" --scheme mdts,abuffer \
            --executor "$executor" --threads "$threads" --frames "$FRAMES" --json --no-images \
            --quiet --out "$OUT/$row-$which" > /dev/null
    done
    python3 - "$OUT/$row" "$spec" <<'EOF'
import json, sys
prefix, spec = sys.argv[1], sys.argv[2]
def rows(side):
    return {r["scheme"]: r for r in map(json.loads, open(f"{prefix}-{side}/bench.jsonl"))
            if r.get("command") == "bench"}
base, new = rows("BASE"), rows("NEW")
for scheme in base:
    b, n = base[scheme], new[scheme]
    stages = lambda r: "/".join(f"{r[k]:.2f}" for k in ("vertex_ms", "passes_ms", "resolve_ms"))
    print(f"{spec} {scheme}: base {b['time_ms']:.2f} ms, new {n['time_ms']:.2f} ms, "
          f"base/new {b['time_ms'] / n['time_ms']:.2f}; vertex/passes/resolve base {stages(b)}, "
          f"new {stages(n)}; lost {b['lost']}/{n['lost']}, mismatched "
          f"{b['mismatched_pixels']}/{n['mismatched_pixels']}")
EOF
    row=$((row + 1))
done
echo "== done in $SECONDS s"

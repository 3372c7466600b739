#!/usr/bin/env bash
# The speed issue's thread sweep (issue 18) in one call of at most 4 minutes, for a machine with
# no cargo: a release `fragsim` binary carried to it runs `bench` on the full dragon at 512² and
# 2048² and on `bunny-spheres` at 512², MDTS and the fixed-capacity A-buffer (FreePipe's
# configurations: K = 20 and 20 slots, one geometry pass), at 1, 2, 4, 8 and 16 threads.
#
#   FRAGSIM=./fragsim MESH=./dragon_vrip.ply.gz OUT=out/device tools/device/scaling.sh
#
# Environment (defaults in brackets):
#   FRAGSIM [target/release/fragsim]   the binary
#   MESH [../shared/meshes/dragon_vrip.ply.gz, from the repository root]   the dragon
#   OUT [target/device-scaling]        where the results go (emptied of earlier results first)
#   THREADS ["1 2 4 8 16"]   EXECUTORS ["parallel tiled"]   SCHEMES [mdts,abuffer]
#   SCENES ["dragon512 dragon2048 bunny-spheres512"]   which of the three scenes to run
#   FRAMES_512 [20]   FRAMES_2048 [8]   timed frames per run (bench reports the median)
#   BUDGET [210]      seconds: a run that would start after this is skipped and named, so that
#                     the call ends within its 4 minutes; the parallel executor's runs go first
#   DRY [unset]       set: print the commands only
#
# Output, in OUT: `bench.jsonl` (every bench record of every run, JSON Lines: docs/json-schema.md,
# each record's context names scene, viewport, threads and executor), one bench table per run named
# `s18-<scene>-t<threads>-<executor>.md` (what scaling.py reads), and on stdout the scaling table
# (`scaling.py`: frame time, fps and efficiency per thread count; it refuses a run with a lost
# fragment or a mismatched pixel), a per-stage table (ns per vertex, triangle and fragment, each
# stage's share) and the chart `scaling.svg`. Not a test: nothing in cargo test or CI runs it.
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
FRAGSIM=${FRAGSIM:-$root/target/release/fragsim}
MESH=${MESH:-$root/../shared/meshes/dragon_vrip.ply.gz}
OUT=${OUT:-$root/target/device-scaling}
THREADS=${THREADS:-1 2 4 8 16}
EXECUTORS=${EXECUTORS:-parallel tiled}
SCHEMES=${SCHEMES:-mdts,abuffer}
FRAMES_512=${FRAMES_512:-20}
FRAMES_2048=${FRAMES_2048:-8}
BUDGET=${BUDGET:-210}
TAG=s18

[ -x "$FRAGSIM" ] || { echo "no fragsim binary at $FRAGSIM (set FRAGSIM)" >&2; exit 2; }
[ -f "$MESH" ] || { echo "no mesh at $MESH (set MESH)" >&2; exit 2; }
mkdir -p "$OUT"
rm -f "$OUT"/bench.jsonl "$OUT"/$TAG-*.md
echo "== $(date -u '+%Y-%m-%d %H:%M:%S UTC'), $(nproc) cores, $(uname -sr), load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "== $FRAGSIM ($("$FRAGSIM" --version 2>/dev/null || echo 'no --version')), schemes $SCHEMES"

# name, scene arguments, frames
scenes=(
    "dragon512|--mesh $MESH --width 512 --height 512|$FRAMES_512"
    "dragon2048|--mesh $MESH --width 2048 --height 2048|$FRAMES_2048"
    "bunny-spheres512|--scene bunny-spheres --width 512 --height 512|$FRAMES_512"
)
skipped=()
for executor in $EXECUTORS; do
    for entry in "${scenes[@]}"; do
        IFS='|' read -r name scene frames <<< "$entry"
        case " ${SCENES:-dragon512 dragon2048 bunny-spheres512} " in
            *" $name "*) ;;
            *) continue ;;
        esac
        for t in $THREADS; do
            run="$OUT/run-$name-t$t-$executor"
            # shellcheck disable=SC2086 # the scene arguments are words
            command=("$FRAGSIM" bench $scene --scheme "$SCHEMES" --executor "$executor"
                --threads "$t" --frames "$frames" --json --no-images --out "$run")
            if [ -n "${DRY:-}" ]; then
                echo "${command[*]}"
                continue
            fi
            if [ "$SECONDS" -ge "$BUDGET" ]; then
                skipped+=("$name t$t $executor")
                continue
            fi
            start=$SECONDS
            "${command[@]}" > /dev/null
            cat "$run/bench.jsonl" >> "$OUT/bench.jsonl"
            cp "$run/bench.md" "$OUT/$TAG-$name-t$t-$executor.md"
            echo "== $name, $t threads, $executor: $((SECONDS - start)) s"
        done
    done
done
[ -n "${DRY:-}" ] && exit 0
for s in "${skipped[@]}"; do echo "== SKIPPED (past the ${BUDGET} s budget): $s"; done

if ! command -v python3 > /dev/null; then
    echo "== no python3 here: the tables are in $OUT (scaling.py turns them into the scaling table)"
    exit 0
fi
echo
echo "== scaling (tools/scaling/scaling.py)"
python3 "$root/tools/scaling/scaling.py" "$OUT" "$TAG" "$OUT/scaling.svg"
echo
echo "== stages per run (medians): ns per vertex, per triangle (geometry passes), per fragment (passes and post pass), shares"
python3 - "$OUT/bench.jsonl" <<'EOF'
import json, sys
print("| scene | viewport | executor | threads | scheme | frame ms | fps | vertex / passes / post ms | ns/vertex | ns/triangle | ns/fragment | shares vertex / passes / post | lost | mismatched px |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for line in open(sys.argv[1]):
    r = json.loads(line)
    c = r.get("context", r)
    viewport = f"{c.get('width', '?')}x{c.get('height', '?')}"
    shares = r.get("shares") or {}
    share = " / ".join(f"{shares.get(k, float('nan')):.0%}" for k in ("vertex", "passes", "resolve"))
    print(f"| {r.get('scene', c.get('scene'))} | {viewport} | {c.get('executor')} | {c.get('threads')} | {r['scheme']} "
          f"| {r['time_ms']:.2f} | {r['fps']:.0f} | {r['vertex_ms']:.2f} / {r['passes_ms']:.2f} / {r['resolve_ms']:.2f} "
          f"| {r.get('ns_per_vertex', float('nan')):.1f} | {r.get('ns_per_triangle', float('nan')):.1f} "
          f"| {r.get('ns_per_fragment', float('nan')):.1f} | {share} | {r['lost']} | {r['mismatched_pixels']} |")
EOF
echo "== done in $SECONDS s"

#!/usr/bin/env bash
# Two fragsim binaries side by side in one run, rounds alternating which goes first, so that a
# shared, noisy machine loads both alike: the ratio of their median frames is what to report
# (issue 18), never absolute times from different runs.
#
#   BEFORE=/tmp/fragsim-before AFTER=target/release/fragsim tools/scaling/ab.sh --mesh M --width 512 --height 512
#
# The arguments are `fragsim bench`'s scene arguments. Environment (defaults in brackets):
#   BEFORE, AFTER      the two binaries (required)
#   ROUNDS [5]   FRAMES [10]   THREADS [cores]   SCHEMES [mdts,abuffer]   EXECUTOR [parallel]
#   WORK [target/ab]   where each run's bench output goes
# Prints each round's median frame per scheme and binary, and per scheme the median over rounds
# of before ÷ after (above 1: AFTER is faster), with lost fragments and mismatched pixels (both
# must be 0). Not a test: nothing in cargo test or CI runs it.
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
: "${BEFORE:?set BEFORE to the starting binary}" "${AFTER:?set AFTER to the new binary}"
ROUNDS=${ROUNDS:-5}
FRAMES=${FRAMES:-10}
THREADS=${THREADS:-$(nproc)}
SCHEMES=${SCHEMES:-mdts,abuffer}
EXECUTOR=${EXECUTOR:-parallel}
WORK=${WORK:-$root/target/ab}
mkdir -p "$WORK"
echo "== $(date -u '+%Y-%m-%d %H:%M:%S UTC'), $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
echo "== bench $* --scheme $SCHEMES --executor $EXECUTOR --threads $THREADS --frames $FRAMES; $ROUNDS rounds"
run() { # $1: before|after, $2: round
    local binary=$BEFORE
    [ "$1" = after ] && binary=$AFTER
    "$binary" bench "${@:3}" --scheme "$SCHEMES" --executor "$EXECUTOR" --threads "$THREADS" \
        --frames "$FRAMES" --json --no-images --out "$WORK/$1-r$2" > /dev/null
}
for round in $(seq 1 "$ROUNDS"); do
    if [ $((round % 2)) -eq 1 ]; then
        run before "$round" "$@"
        run after "$round" "$@"
    else
        run after "$round" "$@"
        run before "$round" "$@"
    fi
    echo "== round $round/$ROUNDS done, load $(cut -d' ' -f1 /proc/loadavg)"
done
python3 - "$WORK" "$ROUNDS" <<'EOF'
import json, statistics, sys
work, rounds = sys.argv[1], int(sys.argv[2])
def rows(side, r):
    return {x["scheme"]: x for x in map(json.loads, open(f"{work}/{side}-r{r}/bench.jsonl"))}
runs = {(side, r): rows(side, r) for side in ("before", "after") for r in range(1, rounds + 1)}
schemes = list(runs[("before", 1)])
print("round | " + " | ".join(f"{s} before ms | {s} after ms | ratio" for s in schemes))
ratios = {s: [] for s in schemes}
for r in range(1, rounds + 1):
    cells = [str(r)]
    for s in schemes:
        b, a = runs[("before", r)][s]["time_ms"], runs[("after", r)][s]["time_ms"]
        ratios[s].append(b / a)
        cells += [f"{b:.2f}", f"{a:.2f}", f"{b / a:.2f}"]
    print(" | ".join(cells))
for s in schemes:
    med = lambda side, key: statistics.median(runs[(side, r)][s][key] for r in range(1, rounds + 1))
    bad = max(runs[(side, r)][s][k] for side in ("before", "after") for r in range(1, rounds + 1)
              for k in ("lost", "mismatched_pixels"))
    print(f"{s}: before {med('before', 'time_ms'):.2f} ms (vertex {med('before', 'vertex_ms'):.2f}, "
          f"passes {med('before', 'passes_ms'):.2f}, post {med('before', 'resolve_ms'):.2f}); "
          f"after {med('after', 'time_ms'):.2f} ms (vertex {med('after', 'vertex_ms'):.2f}, "
          f"passes {med('after', 'passes_ms'):.2f}, post {med('after', 'resolve_ms'):.2f}); "
          f"before/after median {statistics.median(ratios[s]):.2f} "
          f"(min {min(ratios[s]):.2f}, max {max(ratios[s]):.2f}); worst lost or mismatched {bad}")
EOF

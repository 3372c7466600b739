#!/usr/bin/env bash
# fragsim vs Mesa's llvmpipe on the same mesh, in one run, rounds interleaved (README.md here).
#
#   tools/llvmpipe/compare.sh
#
# Environment (defaults in brackets):
#   MESH [../shared/meshes/dragon_vrip.ply.gz]   WIDTH, HEIGHT [512]   VIEW [30]   ELEVATION [15]
#   ROUNDS [5]       rounds; each runs llvmpipe and fragsim once, the order alternating
#   FRAMES [30]      timed frames per run (each side reports its median)
#   SCHEMES [mdts,abuffer]   fragsim schemes (`fragsim bench --scheme`)
#   THREADS [cores]  fragsim's --threads
#   EXECUTOR [parallel]      fragsim's --executor (comma-separated, or `all`)
#   LP_THREADS [default]     llvmpipe thread settings to run each round, space-separated:
#                    `default` leaves LP_NUM_THREADS unset (llvmpipe: one thread per CPU), a
#                    number sets it (0: rasterize on the calling thread)
#   MODE [exact]     exact: llvmpipe draws fragsim's snapped vertices (pixel-exact comparison);
#                    mvp: model-space vertices and fragsim's camera matrix in f32
#   WORK [target/llvmpipe]   where the binaries, the scene and the results go
#   FRAGSIM [unset]  a fragsim binary to time instead of building target/release/fragsim (a
#                    binary kept for a before/after comparison, or one built with other features)
#
# Not a test: nothing in cargo test or CI runs it. Exit status 1 when the pictures differ.
set -euo pipefail

root=$(cd "$(dirname "$0")/../.." && pwd)
here="$root/tools/llvmpipe"
cd "$root"

MESH=${MESH:-$root/../shared/meshes/dragon_vrip.ply.gz}
WIDTH=${WIDTH:-512}
HEIGHT=${HEIGHT:-512}
VIEW=${VIEW:-30}
ELEVATION=${ELEVATION:-15}
ROUNDS=${ROUNDS:-5}
FRAMES=${FRAMES:-30}
SCHEMES=${SCHEMES:-mdts,abuffer}
THREADS=${THREADS:-$(nproc)}
EXECUTOR=${EXECUTOR:-parallel}
LP_THREADS=${LP_THREADS:-default}
MODE=${MODE:-exact}
WORK=${WORK:-$root/target/llvmpipe}
mkdir -p "$WORK"

echo "== $(date -u '+%Y-%m-%d %H:%M:%S UTC'), $(nproc) cores, $(uname -sr), load: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "== mesh $MESH, ${WIDTH}x${HEIGHT}, view $VIEW, elevation $ELEVATION, mode $MODE"
echo "== $ROUNDS rounds x $FRAMES frames; fragsim --threads $THREADS --scheme $SCHEMES --executor $EXECUTOR; llvmpipe: $LP_THREADS"

echo "== building"
if [ -z "${FRAGSIM:-}" ]; then
    cargo build --release --quiet
fi
# The prep tool's own target directory, whatever CARGO_TARGET_DIR says: its path is used below.
env -u CARGO_TARGET_DIR cargo build --release --quiet --manifest-path "$here/prep/Cargo.toml"
if ! cc -O2 -Wall -o "$WORK/draw" "$here/draw.c" -lEGL -lOpenGL; then
    echo "draw.c did not build: install the packages (README.md):" >&2
    echo "  apt-get install -y gcc libegl-dev libopengl-dev libgl-dev libegl-mesa0 libgl1-mesa-dri" >&2
    exit 2
fi
fragsim=${FRAGSIM:-$root/target/release/fragsim}
prep="$here/prep/target/release/fragsim-llvmpipe-prep"

echo "== fragsim's vertex stage and depth complexity (prep)"
"$prep" "$MESH" "$WIDTH" "$HEIGHT" "$VIEW" "$ELEVATION" "$MODE" "$WORK/scene.bin" "$WORK/fragsim.u32" \
    | tee "$WORK/prep.json"

export LIBGL_ALWAYS_SOFTWARE=1 GALLIUM_DRIVER=llvmpipe
run_llvmpipe() { # $1: round, $2: thread setting
    local out="$WORK/llvmpipe-r$1-t$2"
    if [ "$2" = default ]; then
        env -u LP_NUM_THREADS "$WORK/draw" "$WORK/scene.bin" "$FRAMES" "$out.u32" > "$out.json"
    else
        LP_NUM_THREADS="$2" "$WORK/draw" "$WORK/scene.bin" "$FRAMES" "$out.u32" > "$out.json"
    fi
}
run_fragsim() { # $1: round
    "$fragsim" bench --mesh "$MESH" --width "$WIDTH" --height "$HEIGHT" --view "$VIEW" \
        --elevation "$ELEVATION" --scheme "$SCHEMES" --executor "$EXECUTOR" --frames "$FRAMES" --threads "$THREADS" \
        --json --out "$WORK/fragsim-r$1" > /dev/null
}

for round in $(seq 1 "$ROUNDS"); do
    if [ $((round % 2)) -eq 1 ]; then
        for t in $LP_THREADS; do run_llvmpipe "$round" "$t"; done
        run_fragsim "$round"
    else
        run_fragsim "$round"
        for t in $LP_THREADS; do run_llvmpipe "$round" "$t"; done
    fi
    echo "== round $round/$ROUNDS done, load $(cut -d' ' -f1 /proc/loadavg)"
done

python3 - "$WORK" "$ROUNDS" "$LP_THREADS" <<'EOF'
import json, statistics, sys
work, rounds, lp_threads = sys.argv[1], int(sys.argv[2]), sys.argv[3].split()
prep = json.load(open(f"{work}/prep.json"))
# fragsim's bench.jsonl: JSON Lines, one record per scheme and executor (docs/json-schema.md).
fs = {r: [json.loads(l) for l in open(f"{work}/fragsim-r{r}/bench.jsonl") if l.strip()]
      for r in range(1, rounds + 1)}
lp = {(r, t): json.load(open(f"{work}/llvmpipe-r{r}-t{t}.json"))
      for r in range(1, rounds + 1) for t in lp_threads}
schemes = [(row["scheme"], row["executor"], row["threads"]) for row in fs[1]]
def row(r, s, e):
    return next(x for x in fs[r] if x["scheme"] == s and x["executor"] == e)
first = next(iter(lp.values()))
print(f"llvmpipe: {first['renderer']}; fragsim: {fs[1][0]['scene']}, {fs[1][0]['triangles']} triangles")
print("ms per frame (each the median of its run's frames; fragsim's includes the vertex stage)")
head = ["round"] + [f"llvmpipe[{t}]" for t in lp_threads] + [f"{s}/{e}x{n}" for s, e, n in schemes]
head += [f"ratio {t}/{s}/{e}" for t in lp_threads for s, e, _ in schemes]
print(" | ".join(head))
ratios = {(t, s, e): [] for t in lp_threads for s, e, _ in schemes}
for r in range(1, rounds + 1):
    cells = [str(r)] + [f"{lp[(r, t)]['median_ms']:.1f}" for t in lp_threads]
    cells += [f"{row(r, s, e)['time_ms']:.1f}" for s, e, _ in schemes]
    for t in lp_threads:
        for s, e, _ in schemes:
            q = lp[(r, t)]["median_ms"] / row(r, s, e)["time_ms"]
            ratios[(t, s, e)].append(q)
            cells.append(f"{q:.2f}")
    print(" | ".join(cells))
print("median over rounds:")
for t in lp_threads:
    lp_ms = statistics.median(lp[(r, t)]["median_ms"] for r in range(1, rounds + 1))
    print(f"  llvmpipe[{t}] {lp_ms:.1f} ms")
for s, e, n in schemes:
    ms = statistics.median(row(r, s, e)["time_ms"] for r in range(1, rounds + 1))
    vertex = statistics.median(row(r, s, e)["vertex_ms"] for r in range(1, rounds + 1))
    bad = max(row(r, s, e)["mismatched_pixels"] for r in range(1, rounds + 1))
    print(f"  fragsim {s} ({e}, {n} threads) {ms:.1f} ms, of which vertex stage {vertex:.1f} ms; "
          f"mismatched pixels {bad}")
for (t, s, e), q in ratios.items():
    print(f"  ratio llvmpipe[{t}] / fragsim {s} ({e}): median {statistics.median(q):.2f} "
          f"(min {min(q):.2f}, max {max(q):.2f})")
# Load from other processes only adds time: each run's fastest frame is the least disturbed.
print("fastest frames (min over each run's frames), ratio of the fastest per round, median:")
for t in lp_threads:
    for s, e, _ in schemes:
        q = [lp[(r, t)]["min_ms"] / row(r, s, e)["min_ms"] for r in range(1, rounds + 1)]
        lp_min = min(lp[(r, t)]["min_ms"] for r in range(1, rounds + 1))
        fs_min = min(row(r, s, e)["min_ms"] for r in range(1, rounds + 1))
        print(f"  llvmpipe[{t}] {lp_min:.1f} ms / fragsim {s} ({e}) {fs_min:.1f} ms (fastest of "
              f"all rounds); per-round ratio median {statistics.median(q):.2f} "
              f"(min {min(q):.2f}, max {max(q):.2f})")

# The pictures: llvmpipe's per-pixel counts against fragsim's depth complexity.
ref = open(f"{work}/fragsim.u32", "rb").read()
ok = True
for key, res in lp.items():
    if open(f"{work}/llvmpipe-r{key[0]}-t{key[1]}.u32", "rb").read() != ref:
        ok = False
        print(f"  llvmpipe round {key[0]} [{key[1]}]: counts DIFFER from fragsim's")
totals = {res["fragments"] for res in lp.values()}
# Every record of a bench run carries the run's oracle fragment count.
print(f"fragments: fragsim {prep['fragments']} (bench oracle {fs[1][0]['oracle_fragments']}), llvmpipe "
      f"{sorted(totals)}; covered pixels {prep['covered_pixels']}, max depth complexity "
      f"{prep['max_depth_complexity']}")
ok = ok and totals == {prep["fragments"]} and fs[1][0]["oracle_fragments"] == prep["fragments"]
print("pictures: " + ("IDENTICAL, every pixel's fragment count equal" if ok else "DIFFERENT"))
sys.exit(0 if ok else 1)
EOF

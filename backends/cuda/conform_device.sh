#!/usr/bin/env bash
# `fragsim conform` against the CUDA backend on the GPU machine (issue 21: "the atomic schemes
# pass N = 500 cases; the deliberately racy k-buffer fails and its shrunk case is recorded").
#
# Builds fragsim_cuda (`make -C backends/cuda OUT=$W`), then runs the battery with the backend as
# the `--backend` command on each generated case: fragsim writes the case's triangle export
# (`{scene}/scene.tri`), fragsim_cuda scans and captures it on the GPU and writes its dump, which
# `mv` puts where conform reads it (`{out}/`). Three runs side by side (each case starts the
# binary twice, a CUDA context each time: the runs wait on that, not on the GPU), each under
# `timeout`:
#   - mdts, K 4, 500 cases: must pass (exit 0);
#   - abuffer, capacity 4, 500 cases: must pass (fragsim_cuda's `--k` sizes its A-buffer);
#   - kbuffer (the deliberately non-atomic read-all / insert / write-all, dumped in MDTS's layout
#     and so judged by MDTS's promise), K 4, 500 cases: should fail (exit 1) and shrink (proptest's
#     part capped at 64 steps, conform's crop and triangle dropping finish); the shrunk case
#     (scene files, the dump, both lists, replay.sh) is saved under $OUT/kbuffer/case.
# Each run's JSON Lines report is $OUT/<run>.jsonl, its stderr $OUT/<run>.stderr, and a line
# `== <run>: exit N, S s` goes to stdout and $OUT/conform.log.
#
# Run from the repository root: `OUT=/some/dir bash backends/cuda/conform_device.sh`. Needs nvcc
# and the driver, and a release `fragsim` binary (no cargo on the device): FRAGSIM (default
# target/devbin-cuda/fragsim, as run_device.sh). Knobs (environment): CASES (default 500), K
# (default 4), SEED (default 0), PART (seconds per run, default 330: with the build's 90 the whole
# script stays under 8 minutes), FRAGSIM_CUDA (a prebuilt backend binary: skips the build; the CPU
# emulation, `make -C backends/cuda emulate`, checks this script without a GPU, where the serial
# k-buffer is of course correct).
set -uo pipefail
F=${FRAGSIM:-target/devbin-cuda/fragsim}
OUT=${OUT:-/tmp/fragsim-conform-out}
W=${W:-/tmp/fragsim-conform}
CASES=${CASES:-500}
K=${K:-4}
SEED=${SEED:-0}
PART=${PART:-330}
mkdir -p "$OUT" "$W"

main() {
    echo "== device"
    command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
    local cuda=${FRAGSIM_CUDA:-}
    if [ -z "$cuda" ]; then
        echo "== build"
        timeout 90 make -C backends/cuda OUT="$W" || { echo "== build failed"; return 2; }
        cuda=$W/fragsim_cuda
    fi
    cuda=$(realpath "$cuda")
    "$F" --version 2>/dev/null || true
    # run NAME CONFORM_SCHEME CUDA_SCHEME SIZE_PLACEHOLDER [conform options...]
    run() {
        local name=$1 scheme=$2 cuda_scheme=$3 size=$4 start=$SECONDS code
        shift 4
        local backend="'$cuda' {scene}/scene.tri {out}/run --schemes $cuda_scheme --k $size --reps 1 >/dev/null && mv {out}/run/$cuda_scheme/* {out}/"
        rm -rf "${OUT:?}/$name"
        timeout "$PART" "$F" conform --scheme "$scheme" --cases "$CASES" --seed "$SEED" --json \
            --save "$OUT/$name" --backend "$backend" "$@" \
            >"$OUT/$name.jsonl" 2>"$OUT/$name.stderr"
        code=$?
        echo "== $name: exit $code (0 pass, 1 counterexample, 2 error, 124 timed out), $((SECONDS - start)) s" \
            >"$OUT/$name.status"
    }
    run mdts mdts mdts '{k}' --k "$K" &
    run abuffer abuffer abuffer '{capacity}' --capacity "$K" &
    # The k-buffer's dump claims MDTS: conform judges it by MDTS's promise at the same K.
    run kbuffer mdts kbuffer '{k}' --k "$K" --shrink-steps 64 &
    wait
    for name in mdts abuffer kbuffer; do
        cat "$OUT/$name.status"
        head -c 1500 "$OUT/$name.jsonl"
        echo
        tail -3 "$OUT/$name.stderr"
    done
    if [ -f "$OUT/kbuffer/case/replay.sh" ]; then
        echo "== kbuffer's shrunk case ($OUT/kbuffer/case)"
        ls -R "$OUT/kbuffer/case" | head -20
        cat "$OUT/kbuffer/case/replay.sh"
    fi
}

main 2>&1 | tee "$OUT/conform.log"

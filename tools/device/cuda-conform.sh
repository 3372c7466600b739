#!/usr/bin/env bash
# `fragsim conform` against the CUDA backend on the GPU machine (issue 21: "the atomic schemes
# pass N = 500 cases; the deliberately racy k-buffer fails and its shrunk case is recorded").
#
# Builds fragsim_cuda (`make -C backends/cuda OUT=$W`), then runs the battery with the backend as
# the `--backend` command on each generated case: fragsim writes the case's triangle export
# (`{scene}/scene.tri`), fragsim_cuda scans and captures it on the GPU and writes its dump, which
# `mv` puts where conform reads it (`{out}/`). Each run has its own server (`fragsim_cuda --serve`,
# serve.cuh: one process, one CUDA context for all its cases) and the per-case command is its
# client (`fragsim_cuda --client`, which waits at most 20 s for the answer; conform kills a case
# at 30 s); started afresh per case, fragsim_cuda spent about a second a case creating a context
# (docs/journal/2026-12-02-wgpu-h200.md). Three runs side by side, each under `timeout`:
#   - mdts, K 4, 500 cases: must pass (exit 0);
#   - abuffer, capacity 4, 500 cases: must pass (fragsim_cuda's `--k` sizes its A-buffer);
#   - kbuffer (the deliberately non-atomic read-all / insert / write-all, dumped in MDTS's layout
#     and so judged by MDTS's promise), K 4, 500 cases: should fail (exit 1) and shrink (proptest's
#     part capped at 64 steps, conform's crop and triangle dropping finish); the shrunk case
#     (scene files, the dump, both lists, replay.sh) is saved under $OUT/kbuffer/case, with
#     replay_direct.sh, the same replay without a server.
# Each run's JSON Lines report is $OUT/<run>.jsonl, its stderr $OUT/<run>.stderr (a line per case
# passed and per shrinking step: `conform --progress-lines`), its server's output (SCENE and RESULT
# lines, errors) $OUT/<run>.server.log, and a line `== <run>: exit N, S s, <its last progress
# line>` goes to stdout and $OUT/conform.log: a run stopped by `timeout` still says how many cases
# passed.
#
# Run from the repository root: `OUT=/some/dir bash tools/device/cuda-conform.sh`. Needs nvcc
# and the driver, and a release `fragsim` binary (no cargo on the device): FRAGSIM (default
# target/devbin-cuda/fragsim, as cuda-captures.sh). Knobs (environment): CASES (default 500), K
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

# start_server DIR LOG: starts `$CUDA --serve DIR` in the background, its pid in SERVER; returns
# once it is ready (it makes its FIFO once its device is up), non-zero if it never was.
start_server() {
    rm -rf "$1"
    "$CUDA" --serve "$1" >"$2" 2>&1 &
    SERVER=$!
    for _ in $(seq 6000); do
        [ -p "$1/requests" ] && return 0
        kill -0 "$SERVER" 2>/dev/null || return 1
        sleep 0.01
    done
    return 1
}

# stop_server DIR PID: `quit`, or a kill if it is not read (a server that died holds no FIFO).
stop_server() {
    [ -p "$1/requests" ] && timeout 5 sh -c "echo quit >'$1/requests'" 2>/dev/null
    for _ in $(seq 50); do
        kill -0 "$2" 2>/dev/null || break
        sleep 0.1
    done
    kill "$2" 2>/dev/null
    wait "$2" 2>/dev/null
}

# What the server saves a backend run: one small case run 5 times as a process of its own (a CUDA
# context each), then 5 times through a server (whose start, a context, is paid once).
probe_server_saving() {
    local tri=$W/probe.tri serve=$W/probe.serve t0 t1 t2 t3
    "$F" export-scene --scene soup:6:1 --width 8 --height 8 --out "$tri" >/dev/null || return
    t0=$(date +%s%N)
    for _ in 1 2 3 4 5; do
        "$CUDA" "$tri" "$W/probe" --schemes mdts --k 4 --reps 1 >/dev/null || return
    done
    t1=$(date +%s%N)
    start_server "$serve" "$W/probe.server.log" || return
    t2=$(date +%s%N)
    for _ in 1 2 3 4 5; do
        "$CUDA" --client "$serve" --timeout 20 "$tri" "$W/probe" --schemes mdts --k 4 --reps 1 || break
    done
    t3=$(date +%s%N)
    stop_server "$serve" "$SERVER"
    echo "== a backend run of one 8x8 case: $(((t1 - t0) / 5000000)) ms as a process of its own," \
        "$(((t3 - t2) / 5000000)) ms through a server (whose start took $(((t2 - t1) / 1000000)) ms, once)"
}

main() {
    echo "== device"
    command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
    CUDA=${FRAGSIM_CUDA:-}
    if [ -z "$CUDA" ]; then
        echo "== build"
        timeout 90 make -C backends/cuda OUT="$W" || { echo "== build failed"; return 2; }
        CUDA=$W/fragsim_cuda
    fi
    CUDA=$(realpath "$CUDA")
    "$F" --version 2>/dev/null || true
    # A fragsim older than --progress-lines still runs the battery, only silent until its end.
    PROGRESS=--progress-lines
    "$F" conform --help | grep -q -- --progress-lines ||
        { PROGRESS=; echo "== $F has no conform --progress-lines: a stopped run will not say how far it got"; }
    # run NAME CONFORM_SCHEME CUDA_SCHEME SIZE_PLACEHOLDER [conform options...], in a subshell
    # of its own (the runs go side by side), its server stopped however it ends.
    run() (
        local name=$1 scheme=$2 cuda_scheme=$3 size=$4 start=$SECONDS code serve=$W/$1.serve
        shift 4
        rm -rf "${OUT:?}/$name"
        start_server "$serve" "$OUT/$name.server.log"
        code=$?
        trap 'stop_server "$serve" "$SERVER"' EXIT
        if [ "$code" != 0 ]; then
            echo "== $name: its server did not start: $(tail -2 "$OUT/$name.server.log")" >"$OUT/$name.status"
            return
        fi
        local backend="'$CUDA' --client '$serve' --timeout 20 {scene}/scene.tri {out}/run --schemes $cuda_scheme --k $size --reps 1 && mv {out}/run/$cuda_scheme/* {out}/"
        timeout "$PART" "$F" conform --scheme "$scheme" --cases "$CASES" --seed "$SEED" --json \
            --timeout 30 ${PROGRESS:+"$PROGRESS"} --save "$OUT/$name" --backend "$backend" "$@" \
            >"$OUT/$name.jsonl" 2>"$OUT/$name.stderr"
        code=$?
        echo "== $name: exit $code (0 pass, 1 counterexample, 2 error, 124 timed out), $((SECONDS - start)) s," \
            "last: $(grep '^conform: ' "$OUT/$name.stderr" | tail -1)" >"$OUT/$name.status"
    )
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
        # The replay's first line is a client of a server that is gone: the same without one.
        sed "s| --client '[^']*' --timeout [0-9]*||" "$OUT/kbuffer/case/replay.sh" \
            >"$OUT/kbuffer/case/replay_direct.sh"
    fi
    probe_server_saving
}

main 2>&1 | tee "$OUT/conform.log"

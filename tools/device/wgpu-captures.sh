#!/usr/bin/env bash
# The wgpu backend on the device machine in one call (docs/results-gpu.md, "wgpu on the H200";
# issue 17 and issue 16's captures): every scheme, correct and planted, and the non-atomic k-buffer, of the
# bunny, the dragon and bunny-spheres at 512² and 2048², replay and engine mode, views 30° and
# 120° (the planted bugs there too), and views 210° and 300° for the schemes issue 16 asks at 4
# views (abuffer, mdts, mdts32, linked-list-nearest). Each capture is judged in place by
# `fragsim-wgpu capture --judge --precision`: the coverage check (replay mode: fragsim's
# (pixel, primitive) pairs at every pixel the scheme keeps whole, the A-buffer's counters against
# fragsim's depth complexity) and the precision verdict, the library calls of `fragsim compare
# oracle DIR --vertex-precision f32` with its reference built once per view and shared by that
# view's captures. The dumps are not written (--discard: the 2048² linked lists are hundreds of
# megabytes each). The spinlocked k-buffer runs on its own under `timeout` (a spinlock in a
# fragment shader has no forward-progress guarantee: a hang is reported, not waited out).
# --capacity 4 (A-buffer slots, linked-list pool nodes per pixel) so that the fixed A-buffer's
# off-by-one plant has pixels at its capacity to show in; K = 8; elevation 15°.
#
# Carry `target/devbin-wgpu` (`carry: ["target/devbin-wgpu"]`): the stripped release
# `fragsim-wgpu`, the dragon and the Vulkan loader's .debs in gl/ (the device has the NVIDIA
# driver's ICD but maybe no loader); backends/wgpu/README.md says how to fill it. Run
# `bash tools/device/wgpu-captures.sh` from the repository root. Jobs (one per scene, side, view and mode) run side by
# side (the verdicts are CPU work), in the order the knobs give: each side in turn, smallest
# first, so that it is complete whatever happens; within a side views 30° and 120° (the planted
# ones) of every scene first, in SCENES's order (the bunny first by default, so that the bunny
# at 512², both views, both modes, are the first jobs), then the other views. Every job stops at
# the common deadline BUDGET seconds after the start (a job not started by then says so), so the
# call ends in time.
#
# SPINLOCK=0 leaves the spinlocked k-buffer out: on the H200 (2026-12-03) its shaders, killed
# by `timeout`, kept the GPU busy after their processes ended, and every capture started after
# them stalled until the deadline (docs/results-gpu.md, "The spinlocked k-buffer hangs on NVIDIA").
#
# Knobs (environment): SIZES (default "512 2048"), SCENES ("bunny dragon bunny-spheres"), VIEWS
# ("30 120 210 300"), MODES ("replay engine"), JOBS (parallel jobs, default the cores / 2), BUDGET
# (seconds for all the jobs, default 210), BIN (default target/devbin-wgpu), DRAGON (default
# $BIN/dragon_vrip.ply.gz). Exactly the bunny at 512², 2 views, both modes (4 jobs):
# SCENES=bunny SIZES=512 VIEWS="30 120" bash tools/device/wgpu-captures.sh. A dry run on
# lavapipe: BIN=target/release DRAGON=../shared/meshes/dragon_vrip.ply.gz SIZES="32 64" bash
# tools/device/wgpu-captures.sh.
#
# Output: every job's log on stdout and in $OUT/wgpu-device.log, then the summary table (scheme,
# scene, view, size, mode, samples, verdict, error px, ambiguous px, coverage px, differing
# samples/pixels of a per-sample capture, ms: GPU timestamps where the adapter has them, else the
# wall time of submit to read-back) on stdout and in $OUT/wgpu-summary.tsv.
#
# MSAA=1: issue 22's per-sample counting pass instead of the captures (`fragsim-wgpu msaa-count`,
# src/sample_counts.rs): per scene and side one command over every view, mode and sample count,
# the GPU's per-sample fragment counts against fragsim's per-sample oracle at the standard
# positions, and against the positions mirrored in y (which must differ). Defaults then: SIZES
# "512", SCENES "bunny dragon", VIEWS "30 120", MODES "replay engine", SAMPLES "1 4 8" (1: the
# control), BUDGET 240 s for all. Output: each command's log on stdout and in
# $OUT/msaa-device.log, the table of every (scene, side, view, mode, samples) on stdout and in
# $OUT/msaa-summary.md; exit 0 when every replay count is identical, 1 when one differs, 2 when
# a command failed (a sample count the GPU lacks, the budget spent). MSAA_ARGS: more options of
# msaa-count (e.g. "--alone --examples 8": each differing replay sample's triangles drawn alone).
# On the H200:
# MSAA=1 bash tools/device/wgpu-captures.sh. A dry run on lavapipe (1 and 4 samples only):
# MSAA=1 BIN=target/release DRAGON=../shared/meshes/dragon_vrip.ply.gz SIZES=64 SAMPLES="1 4"
# bash tools/device/wgpu-captures.sh.
#
# MSAA=capture: issue 34's per-sample captures instead (`fragsim-wgpu capture --samples N`,
# src/capture.rs): a list per (pixel, sample), each sample's depth interpolated at the sample,
# the schemes with a per-sample variant (abuffer, abuffer-exact, mdts, mdts32, linked-list,
# linked-list-nearest), correct and planted (--plant all: the centre-depth plant too), each
# judged in place by --precision (the library calls of `fragsim compare oracle DIR
# --vertex-precision f32`, per sample). One job per (scene, side, view, mode, samples). Defaults
# then: SIZES "512", SCENES "bunny dragon", VIEWS "30 120", MODES "engine replay", SAMPLES "4 8",
# BUDGET 300 s. The summary table gains the sample count and the differing samples and pixels.
# On the H200: MSAA=capture bash tools/device/wgpu-captures.sh. A dry run on lavapipe:
# MSAA=capture BIN=target/release SCENES=bunny SIZES=64 SAMPLES=4 bash tools/device/wgpu-captures.sh.
set -uo pipefail
msaa=${MSAA:-0}
bin=${BIN:-target/devbin-wgpu}
if [ "$msaa" = 1 ]; then
    sizes=${SIZES:-512} scenes=${SCENES:-"bunny dragon"} views=${VIEWS:-"30 120"} budget=${BUDGET:-240}
elif [ "$msaa" = capture ]; then
    sizes=${SIZES:-512} scenes=${SCENES:-"bunny dragon"} views=${VIEWS:-"30 120"} budget=${BUDGET:-300}
else
    sizes=${SIZES:-"512 2048"} scenes=${SCENES:-"bunny dragon bunny-spheres"}
    views=${VIEWS:-"30 120 210 300"} budget=${BUDGET:-210}
fi
modes=${MODES:-"replay engine"}
# The sample counts of the captures: one a pixel but under MSAA=capture.
if [ "$msaa" = capture ]; then capture_samples=${SAMPLES:-"4 8"}; else capture_samples=1; fi
jobs=${JOBS:-$(( $(nproc) / 2 > 0 ? $(nproc) / 2 : 1 ))}
deadline=$(( $(date +%s) + budget ))
dragon=${DRAGON:-$bin/dragon_vrip.ply.gz}
out=${OUT:-/tmp}
if compgen -G "$bin/gl/*.deb" >/dev/null; then
    for f in "$bin"/gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
fi
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-/tmp}
icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
if ! "$bin/fragsim-wgpu" adapter 2>&1 | grep -q NVIDIA && [ -e "$icd" ]; then
    export VK_DRIVER_FILES=$icd
fi
"$bin/fragsim-wgpu" adapter || exit 1
command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version --format=csv,noheader

# MSAA=1: the counting pass, one command per side and scene (see the header), then the table.
if [ "$msaa" = 1 ]; then
    # wgpu cannot report the driver's standardSampleLocations; vulkaninfo can, where installed.
    command -v vulkaninfo >/dev/null && vulkaninfo 2>/dev/null | grep -m1 standardSampleLocations
    comma() { echo "$*" | tr ' ' ','; }
    log=$out/msaa-device.log status=0
    : >"$log"
    for side in $sizes; do
        for scene in $scenes; do
            case $scene in
                dragon) what=(--mesh "$dragon") ;;
                *) what=(--scene "$scene") ;;
            esac
            left=$((deadline - $(date +%s)))
            if [ "$left" -lt 5 ]; then
                echo "$scene $side: not run, the budget was spent" | tee -a "$log"
                status=2
                continue
            fi
            timeout "$left" "$bin/fragsim-wgpu" msaa-count "${what[@]}" --width "$side" --height "$side" \
                --view "$(comma $views)" --mode "$(comma $modes)" --samples "$(comma ${SAMPLES:-1 4 8})" \
                --mirrored ${MSAA_ARGS:-} 2>&1 | tee -a "$log"
            rc=${PIPESTATUS[0]}
            [ "$rc" -ge 2 ] && { echo "$scene $side: exit $rc (124: stopped at the deadline; 2: a pass could not run, above)" | tee -a "$log"; status=2; }
        done
    done
    echo
    echo "== msaa summary (samples differ: GPU against fragsim's standard positions; mirrored: against (x, 16 - y))"
    {
        grep -m1 '^| scene' "$log"
        grep -m1 '^|---' "$log"
        grep '^| ' "$log" | grep -v '^| scene'
    } | tee "$out/msaa-summary.md"
    if [ "$status" = 0 ] && grep '^| ' "$log" | grep ' replay ' | grep -q DIFFERENT; then
        status=1
    fi
    exit "$status"
fi
logs=$(mktemp -d)
export bin dragon logs deadline

# One job: the captures of one scene, side, view, mode and sample count.
one() {
    local scene=$1 side=$2 view=$3 mode=$4 samples=$5 what schemes plant verdicts
    case $scene in
        dragon) what=(--mesh "$dragon") ;;
        *) what=(--scene "$scene") ;;
    esac
    # Per sample the exact --judge (the single-sample oracle) does not apply: --precision alone.
    if [ "$samples" = 1 ]; then verdicts=(--judge --precision); else verdicts=(--precision); fi
    local common=("${what[@]}" --width "$side" --height "$side" --view "$view" --mode "$mode"
        --k 8 --capacity 4 --samples "$samples" "${verdicts[@]}" --discard)
    case $samples-$view in
        1-30 | 1-120) schemes=abuffer,abuffer-exact,mdts,mdts32,kbuffer,linked-list,linked-list-nearest plant=all ;;
        1-*) schemes=abuffer,mdts,mdts32,linked-list-nearest plant=none ;;
        *) schemes=abuffer,abuffer-exact,mdts,mdts32,linked-list,linked-list-nearest plant=all ;;
    esac
    local log=$logs/$scene-$side-$view-$mode-$samples.log start=$SECONDS left
    {
        echo "== $scene ${side}x${side} view $view $mode, $samples sample(s) a pixel"
        left=$((deadline - $(date +%s)))
        if [ "$left" -lt 5 ]; then
            echo "job $scene $side $view $mode $samples: not run, the budget was spent"
        else
            timeout "$left" "$bin/fragsim-wgpu" capture --scheme "$schemes" --plant "$plant" "${common[@]}" \
                || echo "job $scene $side $view $mode $samples: exit $? (124: stopped at the deadline)"
        fi
        left=$((deadline - $(date +%s)))
        if [ "$plant" = all ] && [ "$samples" = 1 ] && [ "${SPINLOCK:-1}" = 1 ] && [ "$left" -ge 5 ]; then
            timeout "$((left < 60 ? left : 60))" "$bin/fragsim-wgpu" capture --scheme kbuffer-spinlock-fixed "${common[@]}" \
                || echo "kbuffer-spinlock-fixed $scene $side $view $mode: exit $? (124: timed out, at most 60 s)"
        fi
        echo "== $scene ${side}x${side} view $view $mode $samples: $((SECONDS - start)) s"
    } >"$log" 2>&1
}
export -f one

# The jobs in order: the smaller sides first; within a side the planted views (30°, 120°) of
# every scene, then the other views; the sample counts innermost.
for side in $(echo "$sizes" | tr ' ' '\n' | sort -n); do
    for planted in yes no; do
        for scene in $scenes; do
            for view in $views; do
                case $view in 30 | 120) [ $planted = yes ] ;; *) [ $planted = no ] ;; esac || continue
                for mode in $modes; do
                    for samples in $capture_samples; do
                        echo "$scene $side $view $mode $samples"
                    done
                done
            done
        done
    done
done | xargs -P "$jobs" -L 1 bash -c 'one "$@"' _
cat "$logs"/*.log | tee "$out/wgpu-device.log"

# The table: one row per capture, from each job's capture lines and the verdicts below them
# (per sample, error_px and ambiguous_px count samples, and the per-sample line adds the
# differing samples and pixels).
summary() {
    printf 'scheme\tscene\tview\tsize\tmode\tsamples\tverdict\terror_px\tambiguous_px\tcoverage_px\tdiffering_samples/pixels\tms\n'
    for f in "$logs"/*.log; do
        local base scene side view mode samples
        base=$(basename "$f" .log)
        samples=${base##*-}; base=${base%-*}
        mode=${base##*-}; base=${base%-*}
        view=${base##*-}; base=${base%-*}
        side=${base##*-}; scene=${base%-*}
        awk -v scene="$scene" -v view="$view" -v side="$side" -v mode="$mode" -v samples="$samples" '
            function flush() {
                if (row != "") printf "%s\t%s\t%s\n", row, per, ms
                row = ""
            }
            / triangles, GPU / {
                flush()
                name = $1
                if ($2 == "(planted:") { p = $3; sub(/\)$/, "", p); name = name "+" p }
                ms = $0; sub(/.*GPU /, "", ms); sub(/,.*/, "", ms)
                if (ms ~ /n\/a/) { ms = $0; sub(/.*wall /, "", ms); sub(/ ms.*/, " ms (wall)", ms) }
                cov = "-"
            }
            /^  verdict \(depth ulps/ { cov = $0; sub(/.*coverage: /, "", cov); sub(/ of .*/, "", cov)
                c = $0; if (sub(/.*counters differ at /, "", c)) { sub(/ pixels.*/, "", c); cov = cov "/" c } }
            /^  precision verdict/ {
                v = $6; sub(/:$/, "", v); err = $7
                amb = $0; sub(/ ambiguous,.*/, "", amb); sub(/.*\), /, "", amb)
                row = name "\t" scene "\t" view "\t" side "\t" mode "\t" samples "\t" v "\t" err "\t" amb "\t" cov
                per = "-"
            }
            /^  per sample \(/ { per = $6 "/" $12 }
            END { flush() }' "$f"
    done
}
echo
echo "== summary (coverage px: pixels whose primitive ids or counts differ from fragsim's / A-buffer counters that differ; ms: GPU timestamps)"
# The table aligned where `column` exists (the H200 machine has none: its summary was lost once).
summary > "$out/wgpu-summary.tsv"
if command -v column > /dev/null; then
    column -t -s $'\t' "$out/wgpu-summary.tsv"
else
    cat "$out/wgpu-summary.tsv"
fi
rm -rf "$logs"

#!/usr/bin/env bash
# The wgpu backend on the device machine (docs/results-gpu.md, "wgpu"): one call of the device
# tool with `carry: ["target/devbin-wgpu"]`, which holds the stripped x86-64 `fragsim-wgpu`, the
# dragon and the Vulkan loader's .deb (the machine has the NVIDIA driver's ICD but maybe no
# loader). Every scheme, correct and planted (`--plant all`: the correct shader and each plant
# that applies to it), and the non-atomic k-buffer, of the bunny, the dragon and bunny-spheres at
# 512² and 2048², two views each, replay and engine mode, judged in place (--judge) against
# fragsim's oracle. The three scenes run side by side (the oracle and the verdicts are CPU work);
# the dumps are not written (--discard: at most 8 files come back, and the 2048² linked lists
# are a gigabyte each). The spinlocked k-buffer runs on its own under `timeout`: a spinlock in a
# fragment shader has no forward-progress guarantee, so a hang is reported, not waited out.
# --capacity 4 (A-buffer slots, linked-list pool nodes per pixel) so that the fixed A-buffer's
# off-by-one plant has pixels at its capacity to show in (the bunny has none at 20).
# The logs are the result: $OUT/wgpu-<scene>.log, and everything on stdout.
set -uo pipefail
bin=target/devbin-wgpu
for f in "$bin"/gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export XDG_RUNTIME_DIR=/tmp
if ! "$bin/fragsim-wgpu" adapter 2>&1 | grep -q NVIDIA; then
    export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
fi
"$bin/fragsim-wgpu" adapter || exit 1
nvidia-smi --query-gpu=name,driver_version --format=csv,noheader
logs=${OUT:-/tmp}
schemes=abuffer,abuffer-exact,mdts,mdts32,kbuffer,linked-list,linked-list-nearest

one_scene() {
    local scene=$1 what
    case $scene in
        dragon) what=(--mesh "$bin/dragon_vrip.ply.gz") ;;
        *) what=(--scene "$scene") ;;
    esac
    for side in 512 2048; do
        for view in 30 120; do
            for mode in replay engine; do
                local common=("${what[@]}" --width "$side" --height "$side" --view "$view"
                    --mode "$mode" --k 8 --capacity 4 --judge --discard --depth-ulps 0,256)
                echo "== $scene ${side}x${side} view $view $mode"
                "$bin/fragsim-wgpu" capture --scheme "$schemes" --plant all "${common[@]}"
                timeout 60 "$bin/fragsim-wgpu" capture --scheme kbuffer-spinlock-fixed "${common[@]}" \
                    || echo "kbuffer-spinlock-fixed $mode ${side}x${side}: exit $? (124: timed out after 60 s)"
            done
        done
    done
}

for scene in bunny dragon bunny-spheres; do
    one_scene "$scene" >"$logs/wgpu-$scene.log" 2>&1 &
done
wait
cat "$logs"/wgpu-bunny.log "$logs"/wgpu-dragon.log "$logs"/wgpu-bunny-spheres.log

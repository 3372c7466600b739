#!/usr/bin/env bash
# The wgpu backend on the device machine (docs/results-gpu.md, "wgpu"): one call of the device
# tool with `carry: ["target/devbin-wgpu"]`, which holds the stripped x86-64 `fragsim-wgpu`, the
# dragon and the Vulkan loader's .deb (the machine has the NVIDIA driver's ICD but maybe no
# loader). Every capture is judged in place (--judge) against fragsim's oracle; the log is the
# result (dumps stay on the machine: at most 8 files come back).
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
work=/tmp/wgpu-dumps
for scene in bunny dragon; do
    if [ "$scene" = dragon ]; then what=(--mesh "$bin/dragon_vrip.ply.gz"); else what=(--scene bunny); fi
    for side in 512 2048; do
        views="30"
        [ "$side" = 512 ] && views="30 120"
        for view in $views; do
            for mode in replay engine; do
                echo "== $scene ${side}x${side} view $view $mode"
                "$bin/fragsim-wgpu" capture --scheme abuffer,mdts,mdts32,kbuffer "${what[@]}" \
                    --width "$side" --height "$side" --view "$view" --mode "$mode" --k 8 \
                    --capacity 20 --out "$work/$scene-$side-$view-$mode" --judge --depth-ulps 0,4,256
            done
        done
    done
done

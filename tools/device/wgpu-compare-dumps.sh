#!/usr/bin/env bash
# The wgpu captures written as dumps and judged by `fragsim compare` on the H200 (from the
# repository root, target/devbin-wgpu carried: backends/wgpu/README.md): every wgpu scheme,
# correct and planted, of the bunny and bunny-spheres at 512², two views, replay and engine
# mode, each dump judged by `fragsim compare oracle DUMP --vertex-precision f32` (the precision
# verdict, issue 16).
set -uo pipefail
bin=target/devbin-wgpu
for f in "$bin"/gl/*.deb; do dpkg -x "$f" /; done
ldconfig
export XDG_RUNTIME_DIR=/tmp
"$bin/fragsim-wgpu" adapter 2>&1 | grep -q NVIDIA || export VK_DRIVER_FILES=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
"$bin/fragsim-wgpu" adapter || exit 1
schemes=abuffer,abuffer-exact,mdts,mdts32,kbuffer,linked-list,linked-list-nearest
one() {
  local scene=$1 view=$2 mode=$3 d=/tmp/c/$1-$2-$3
  mkdir -p "$d"
  "$bin/fragsim-wgpu" capture --scene "$scene" --width 512 --height 512 --view "$view" --mode "$mode" \
      --scheme "$schemes" --plant all --k 8 --capacity 4 --out "$d" --judge --depth-ulps 256 > "$d.capture.log" 2>&1
  for s in "$d"/*/; do
    echo "== $scene view $view $mode $(basename "$s"): $("$bin/fragsim" compare oracle "$s" --vertex-precision f32 --no-images --quiet 2>&1 | grep -E '^pixels|^precision|^fragments|^verdict' | sed -E 's/, [0-9]+ clipped.*//; s/, overflowed by design [0-9]+//' | tr '\n' ' ' | cut -c1-700)"
  done > "$d.verdict.log"
  rm -rf "$d"
}
for scene in bunny bunny-spheres; do for view in 30 120; do for mode in replay engine; do
  one $scene $view $mode &
done; done; done
wait
mkdir -p "$OUT"
cat /tmp/c/*.verdict.log | tee "$OUT/verdicts.log"
cat /tmp/c/*.capture.log > "$OUT/captures.log"

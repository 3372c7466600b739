#!/usr/bin/env bash
# The whole device session in one command (docs/results-gpu.md records its output).
# Run from the repository root on the GPU machine, with the x86-64 `fragsim` binary and the
# meshes carried in target/devbin-cuda/ (see backends/cuda/README.md). Writes its logs under $OUT.
set -u
BIN=target/devbin-cuda
F=$BIN/fragsim
OUT=${OUT:-/tmp/fragsim-gpu-out}
W=/tmp/fragsim-gpu
REPS=${REPS:-20}
SIZES=${SIZES:-"512 2048"}
mkdir -p "$OUT" "$W"

main() {
echo "== device"
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm --format=csv,noheader
nvcc --version | tail -1
nproc
echo "== build"
# One translation unit: fragsim_cuda.cu and the headers that mirror the Rust tree (README.md).
make -C backends/cuda OUT="$W" || exit 1
chmod +x "$F"

scene_args() { # tag -> fragsim scene options
  case "$1" in
    bunny) echo "--scene bunny" ;;
    spheres8) echo "--scene spheres:8" ;;
    horse) echo "--mesh $BIN/horse.obj" ;;
    dragon) echo "--mesh $BIN/dragon_vrip.ply.gz" ;;
  esac
}

for size in $SIZES; do
  for scene in bunny dragon horse spheres8; do
    tag=$scene-$size
    args="$(scene_args $scene) --width $size --height $size --view 30 --elevation 15"
    echo "== $tag"
    $F export-scene $args --out "$W/$tag.tri" || continue
    "$W/fragsim_cuda" "$W/$tag.tri" "$W/$tag" --reps "$REPS" | sed "s/^/$tag /"
    if [ "$size" = 512 ] && { [ "$scene" = bunny ] || [ "$scene" = dragon ]; }; then
      # FreePipe's Table 3 allocates 20 layers: the same storage, for the like-for-like timing.
      "$W/fragsim_cuda" "$W/$tag.tri" "$W/$tag-k20" --k 20 --schemes mdts,abuffer --reps "$REPS" \
        | sed "s/^/$tag-k20 /"
    fi
    # fragsim's CPU executors on this machine's cores, same scene (GPU idle by now); `abuffer` is
    # FreePipe's fixed arrays, as the GPU's (it was called `abuffer-fixed` before the catalog).
    $F render $args --json --no-images --scheme mdts,mdts32,abuffer > "$W/cpu-$tag.json" \
      && echo "$tag CPU $(tr -d ' \n' < "$W/cpu-$tag.json")"
    # The verdicts, in parallel (each compare rebuilds the oracle from the dump's header).
    for d in "$W/$tag"/* "$W/$tag-k20"/*; do
      [ -f "$d/dump.json" ] || continue
      name=$(basename "$(dirname "$d")")-$(basename "$d")
      img=/dev/null
      case "$name" in *-512-kbuffer) img="$OUT/diff-$name.png" ;; esac
      ( $F compare oracle "$d" --json --show 2 --image "$W/diff-$name.png" > "$W/cmp-$name.json"; \
        echo "$name compare exit $?" ; [ "$img" != /dev/null ] && cp "$W/diff-$name.png" "$img" ) &
    done
    wait
    for f in "$W"/cmp-$tag-*.json; do
      [ -f "$f" ] && echo "$(basename "$f" .json) $(python3 -c 'import json,sys; r=json.loads(open(sys.argv[1]).readline()); print(json.dumps({k: r[k] for k in r if k == "equal" or k == "compared" or k.endswith("_pixels") or k in ("captured", "lost", "extra", "overflowed", "reported_overflow")}))' "$f")"
    done
    # One text report of the broken variant, to show the side-by-side lists.
    [ "$size" = 512 ] && $F compare oracle "$W/$tag/kbuffer" --show 2 --no-images | head -40
    rm -rf "$W/$tag" "$W/$tag-k20"
  done
done
}

main 2>&1 | tee "$OUT/device.log"
python3 backends/cuda/summarize.py "$OUT/device.log" > "$OUT/summary.md" && cat "$OUT/summary.md"

#!/usr/bin/env bash
# Checks that two builds of the backend give the same results: runs OLD and NEW (two fragsim_cuda
# or fragsim_emulate binaries) on each triangle export with the same options, then compares every
# array file byte for byte (cmp) and every dump.json and stdout line with the timings taken out
# (the "extra" line of a header, count_pass_ms and "timings" of the SCENE and RESULT lines).
# Prints one line per dump and exits 1 on any difference. The broken k-buffer races on a GPU, so
# there it differs from run to run whatever the build: pass --schemes mdts,mdts32,abuffer there.
# Usage: same_dumps.sh OLD NEW WORKDIR 'OPTIONS' TRI...
set -u
old=$1 new=$2 work=$3 opts=$4
shift 4
status=0
mkdir -p "$work/old" "$work/new" || exit 2
strip_times() { sed -e 's/"count_pass_ms": [0-9.]*, //' -e 's/, "timings": {[^}]*}//' "$1"; }
for tri in "$@"; do
  tag=$(basename "$tri" .tri)
  for side in old new; do
    bin=$old; [ $side = new ] && bin=$new
    rm -rf "$work/$side/$tag"
    # shellcheck disable=SC2086 # the options are words
    "$bin" "$tri" "$work/$side/$tag" $opts > "$work/$side/$tag.out"
    code=$?
    [ $code = 0 ] || { echo "$tag: $side build exited $code"; status=1; }
  done
  if ! diff <(strip_times "$work/old/$tag.out") <(strip_times "$work/new/$tag.out") > /dev/null; then
    echo "$tag stdout DIFFERS"; status=1
  fi
  if ! diff <(ls "$work/old/$tag") <(ls "$work/new/$tag") > /dev/null; then
    echo "$tag: the builds wrote different dump directories"; status=1
  fi
  for d in "$work/old/$tag"/*/; do
    name=$(basename "$d")
    verdict=same
    for f in "$d"*; do
      base=$(basename "$f")
      if [ "$base" = dump.json ]; then
        diff <(grep -v '"extra"' "$f") <(grep -v '"extra"' "$work/new/$tag/$name/$base") > /dev/null || verdict="DIFFERS ($base)"
      else
        cmp -s "$f" "$work/new/$tag/$name/$base" || verdict="DIFFERS ($base)"
      fi
    done
    [ "$(ls "$d" | wc -l)" = "$(ls "$work/new/$tag/$name" 2>/dev/null | wc -l)" ] || verdict="DIFFERS (file count)"
    [ "$verdict" = same ] || status=1
    echo "$tag $name: $verdict ($(cat "$d"* | wc -c) bytes)"
  done
done
exit $status

#!/usr/bin/env python3
"""The approximate OIT schemes' per-K table (docs/results.md) and per-bucket tables
(docs/journal/2026-12-02-approximate-oit.md), read from the JSON Lines run.sh keeps:
python3 tables.py DIR (run.sh's $O)."""
import json
import sys
from pathlib import Path

BUCKETS = ["1", "2_4", "5_8", "9_16", "17_32", "33+"]


def records(path):
    return [json.loads(line) for line in path.read_text().splitlines()]


def name(r):
    """A row as bench.md labels it: the catalog's by executor, the approximate ones as blends."""
    if r["record"] == "bench-approximate":
        return r["scheme"] + (f" (blend, K = {r['nodes']})" if r["nodes"] else " (blend)")
    return f"{r['scheme']} ({r['executor']})"


def colour(r, suffix=""):
    """EPR %, the channels' mean error, the largest error and the PSNR of a row or a bucket."""
    pixels = r.get("pixels" + suffix) if suffix else r["covered_pixels"]
    errors = r["error_pixels" + suffix]
    mean = r["mean_abs_error" + suffix]
    if not pixels or mean is None:
        return "–"
    psnr = r["psnr_db" + suffix]
    return "{:.3f} % / {:.3f} / {} / {}".format(
        100 * errors / pixels,
        sum(mean) / 3,
        max(r["max_abs_error" + suffix]),
        "∞" if psnr is None else f"{psnr:.2f}",
    )


def main(out):
    print("Per K on bunny-spheres: EPR / mean err / max err / PSNR dB, whole image")
    print("| K | mdts | mlab (blend) | tail-blend (blend) |\n|---|---|---|---|")
    runs = {k: records(out / f"bunny-spheres-k{k}.jsonl") for k in (2, 4, 8, 16, 32)}
    # MDTS's catalog row and the blends' images (the K = 8 runs hold the catalog's `mlab` too).
    kinds = {"mdts": "bench", "mlab": "bench-approximate", "tail-blend": "bench-approximate"}

    def row(rows, scheme):
        return next(r for r in rows if r["scheme"] == scheme and r["record"] == kinds[scheme])

    for k, rows in runs.items():
        print(f"| {k} | " + " | ".join(colour(row(rows, s)) for s in kinds) + " |")
    for scheme in kinds:
        print(f"\nPer K and bucket on bunny-spheres, {scheme}: EPR / mean err / max err / PSNR dB")
        print("| K | " + " | ".join(b.replace("_", "–") for b in BUCKETS) + " |")
        print("|---" * (len(BUCKETS) + 1) + "|")
        for k, rows in runs.items():
            r = row(rows, scheme)
            print(f"| {k} | " + " | ".join(colour(r, f"_dc_{b}") for b in BUCKETS) + " |")
    for scene in ("bunny", "dragon", "bunny-spheres"):
        for k in (8, 4):
            print(f"\n{scene}, K = {k}: EPR / mean err / max err / PSNR dB")
            print("| row | whole image | " + " | ".join(b.replace("_", "–") for b in BUCKETS) + " |")
            print("|---" * (len(BUCKETS) + 2) + "|")
            for r in records(out / f"{scene}-k{k}.jsonl"):
                cells = [colour(r, f"_dc_{b}") for b in BUCKETS]
                print(f"| {name(r)} | {colour(r)} | " + " | ".join(cells) + " |")
            print("| pixels | " + str(r["covered_pixels"]) + " | "
                  + " | ".join(str(r[f"pixels_dc_{b}"]) for b in BUCKETS) + " |")


main(Path(sys.argv[1]))

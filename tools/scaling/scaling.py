#!/usr/bin/env python3
"""Scaling table and chart from the `fragsim bench` tables of a thread sweep.

Reads `<TAG>-<mesh>-t<threads>-<executor>.md` files (written by
docs/measurements/device-2026-11-23-issue9/scaling.sh) and prints a markdown table of frame time,
fps and parallel efficiency (1-thread frame time of the same executor / (threads x frame time)),
and writes an SVG chart of fps per thread count. Standard library only: this is a docs helper,
not part of the project's code or tests.

usage: scaling.py DIR TAG OUT.svg
"""
import glob
import os
import re
import sys

directory, tag, svg_path = sys.argv[1:4]
rows = {}  # (mesh, executor, scheme) -> {threads: (frame_ms, fps)}
for path in glob.glob(os.path.join(directory, f"{tag}-*-t*-*.md")):
    match = re.match(rf"{re.escape(tag)}-(.+)-t(\d+)-(\w+)\.md$", os.path.basename(path))
    mesh, threads, executor = match.group(1), int(match.group(2)), match.group(3)
    # Columns by their header names: bench's table gains columns (it did, and this script then
    # read the vertex stage's time as the frame's), so no position is assumed.
    column, width = None, 0
    for line in open(path):
        cells = [c.strip() for c in line.split("|")]
        if len(cells) > 2 and cells[1] == "scheme":
            column, width = {name: i for i, name in enumerate(cells)}, len(cells)
            missing = {"lost", "mismatched px", "frame ms", "fps"} - column.keys()
            if missing:
                sys.exit(f"{path}: the bench table has no column {sorted(missing)}")
        elif column and len(cells) == width and cells[1] in ("mdts", "mdts-probe", "abuffer"):
            lost, mismatched = cells[column["lost"]], cells[column["mismatched px"]]
            if lost != "0" or mismatched != "0":
                sys.exit(f"{path}: {cells[1]} lost {lost}, mismatched {mismatched}")
            rows.setdefault((mesh, executor, cells[1]), {})[threads] = (
                float(cells[column["frame ms"]]), float(cells[column["fps"]]))

print("| mesh | executor | scheme | " + " | ".join(f"{t} thr ms (fps, eff.)" for t in (1, 2, 4, 8, 16)) + " |")
print("|---|---|---|" + "---|" * 5)
for (mesh, executor, scheme), by_threads in sorted(rows.items()):
    if executor == "serial":
        continue
    base = by_threads.get(1, (None,))[0]
    cells = []
    for t in (1, 2, 4, 8, 16):
        # A sweep cut short (tools/device/scaling.sh's time budget) leaves thread counts out: a dash, not a crash.
        if t not in by_threads:
            cells.append("–")
            continue
        ms, fps = by_threads[t]
        efficiency = f", {base / (t * ms):.0%}" if base else ""
        cells.append(f"{ms:.2f} ({fps:.0f}{efficiency})")
    print(f"| {mesh} | {executor} | {scheme} | " + " | ".join(cells) + " |")

# The chart: fps against threads (log2 axis), one line per (mesh, executor, scheme).
width, height, left, bottom, top, right = 760, 440, 60, 50, 20, 250
plot_w, plot_h = width - left - right, height - top - bottom
lines = [(k, v) for k, v in sorted(rows.items()) if k[1] != "serial"]
fps_max = max(fps for _, v in lines for _, fps in v.values())
fps_max = (int(fps_max / 100) + 1) * 100
x_of = lambda t: left + plot_w * {1: 0, 2: 1, 4: 2, 8: 3, 16: 4}[t] / 4
y_of = lambda fps: top + plot_h * (1 - fps / fps_max)
colours = ["#1b9e77", "#d95f02", "#7570b3", "#e7298a", "#66a61e", "#e6ab02", "#a6761d", "#666666",
           "#1f78b4", "#b2df8a", "#fb9a99", "#cab2d6"]
svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" font-family="sans-serif" font-size="11">',
       f'<rect width="{width}" height="{height}" fill="white"/>']
for fps in range(0, fps_max + 1, 100):
    y = y_of(fps)
    svg.append(f'<line x1="{left}" y1="{y}" x2="{left + plot_w}" y2="{y}" stroke="#ddd"/>')
    svg.append(f'<text x="{left - 6}" y="{y + 4}" text-anchor="end">{fps}</text>')
for t in (1, 2, 4, 8, 16):
    svg.append(f'<text x="{x_of(t)}" y="{top + plot_h + 16}" text-anchor="middle">{t}</text>')
svg.append(f'<text x="{left + plot_w / 2}" y="{height - 12}" text-anchor="middle">threads</text>')
svg.append(f'<text x="14" y="{top + plot_h / 2}" transform="rotate(-90 14 {top + plot_h / 2})" text-anchor="middle">frames per second (vertex stage + passes + post pass)</text>')
for gpu_fps, label in ((297, "GTX 280 MDTS 297 fps"), (363, "GTX 280 A-buffer 363 fps")):
    if gpu_fps <= fps_max:
        y = y_of(gpu_fps)
        svg.append(f'<line x1="{left}" y1="{y}" x2="{left + plot_w}" y2="{y}" stroke="#c00" stroke-dasharray="4 3"/>')
        svg.append(f'<text x="{left + 4}" y="{y - 3}" fill="#c00">{label} (dragon)</text>')
for i, ((mesh, executor, scheme), by_threads) in enumerate(lines):
    colour = colours[i % len(colours)]
    points = " ".join(f"{x_of(t)},{y_of(fps)}" for t, (_, fps) in sorted(by_threads.items()))
    dash = ' stroke-dasharray="5 3"' if executor == "tiled" else ""
    svg.append(f'<polyline points="{points}" fill="none" stroke="{colour}" stroke-width="1.8"{dash}/>')
    y = top + 14 * i + 6
    svg.append(f'<line x1="{width - right + 10}" y1="{y}" x2="{width - right + 34}" y2="{y}" stroke="{colour}" stroke-width="1.8"{dash}/>')
    svg.append(f'<text x="{width - right + 40}" y="{y + 4}">{mesh} {scheme} {executor}</text>')
svg.append("</svg>")
open(svg_path, "w").write("\n".join(svg))

#!/usr/bin/env python3
"""Markdown tables of docs/results.md from the JSON that tools/device/remeasure.sh wrote.

Usage: tables.py DIR   (prints every table, headed by the file it comes from)
"""
import json
import sys
from pathlib import Path


def records(path):
    """The records of a `--json` output: JSON Lines, one record a line (docs/json-schema.md)."""
    return [json.loads(line) for line in open(path) if line.strip()]


def n(x):
    return f"{x:,}"


def passes(row):
    return f"{row['passes']}" + (" (c)" if row.get("count_pass_ms") is not None else "")


def render_table(rows):
    by = {}
    for r in rows:
        by.setdefault(r["scheme"], {})[r["executor"]] = r
    out = ["| scheme | guarantee | passes | memory B | serial ms | parallel ms | tiled ms | overflow | lost (parallel) | mismatched px (parallel) | verdict (all executors) |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for scheme, ex in by.items():
        p = ex["parallel"]
        verdict = "kept" if all(e["keeps_guarantee"] for e in ex.values()) else "**BROKEN**"
        out.append(f"| {scheme} | {p['guarantee']} | {passes(p)} | {n(p['memory_bytes'])} | "
                   f"{ex['serial']['time_ms']:.2f} | {p['time_ms']:.2f} | {ex['tiled']['time_ms']:.2f} | "
                   f"{n(p['overflowed'])} | {n(p['lost'])} | {n(p['mismatched_pixels'])} | {verdict} |")
    return "\n".join(out)


def bench_table(rows):
    report = rows[0]
    head = (f"scene {report['scene']}: {n(report['triangles'])} triangles, {report['width']}×{report['height']}, "
            f"{n(report['oracle_fragments'])} fragments, max depth complexity {report['max_depth_complexity']}, "
            f"{n(report['covered_pixels'])} covered pixels; effect {report['effect']}; {report['frames']} frames per scheme")
    out = [head, "", "| scheme | guarantee | passes | memory B | B/px | captured | overflow | lost | EPR | median ms | min–max ms | vs DP | verdict |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        epr = "—" if r["error_pixel_rate"] is None else f"{100 * r['error_pixel_rate']:.3f} %"
        vs = "—" if r["speedup_vs_depth_peeling"] is None else f"{r['speedup_vs_depth_peeling']:.2f}×"
        verdict = "kept" if r["keeps_guarantee"] else "**BROKEN**"
        out.append(f"| {r['scheme']} | {r['guarantee']} | {passes(r)} | {n(r['memory_bytes'])} | {r['bytes_per_pixel']:.0f} | "
                   f"{n(r['captured'])} | {n(r['overflowed'])} | {n(r['lost'])} | {epr} | {r['time_ms']:.2f} | "
                   f"{r['min_ms']:.2f}–{r['max_ms']:.2f} | {vs} | {verdict} |")
    return "\n".join(out)


def shipping_table(d):
    ks = [1, 2, 4, 8, 16]
    out = ["| scheme | guarantee | mesh | " + " | ".join(f"K = {k}" for k in ks) + " |",
           "|---|---|---|" + "---|" * len(ks)]
    eprs = {}
    for mesh in ["bunny", "dragon"]:
        cells = {}
        guarantee = {}
        for k in ks:
            for r in records(d / f"ship-{mesh}-{k}.json"):
                cells.setdefault(r["scheme"], []).append(
                    f"{n(r['overflowed'])} / {n(r['lost'])} / {n(r['mismatched_pixels'])}")
                guarantee[r["scheme"]] = r["guarantee"].replace(f"({k})", "(K)")
                eprs.setdefault((mesh, r["scheme"]), []).append(
                    "—" if r["error_pixel_rate"] is None else f"{100 * r['error_pixel_rate']:.3f} %")
        for scheme, c in cells.items():
            out.append(f"| `{scheme}` | {guarantee[scheme]} | {mesh} | " + " | ".join(c) + " |")
    out.append("")
    out.append("EPR per K (" + ", ".join(map(str, ks)) + "):")
    for (mesh, scheme), e in eprs.items():
        out.append(f"- {mesh} `{scheme}`: " + " / ".join(e))
    return "\n".join(out)


def sweep_summary(path):
    rows = records(path)
    schemes = list(dict.fromkeys(r["scheme"] for r in rows))
    angles = len({r["view_degrees"] for r in rows})
    out = [f"{path.name} ({rows[0]['effect']}, {angles} angles): mean EPR, max EPR, median time ms"]
    for scheme in schemes:
        mine = [r for r in rows if r["scheme"] == scheme]
        rates = [r["error_pixel_rate"] for r in mine if r["error_pixel_rate"] is not None]
        times = sorted(r["time_ms"] for r in mine)
        out.append(f"- {scheme}: {100 * sum(rates) / len(rates):.3f} %, {100 * max(rates):.3f} %, "
                   f"{times[len(times) // 2]:.2f}")
    return "\n".join(out)


def bench_summary(path):
    rows = records(path)
    return "\n".join(f"- {path.name} {r['scheme']} ({r['executor']}, {r['threads']} thr): median {r['time_ms']:.2f} ms "
                     f"({r['fps']:.0f} fps), passes {passes(r)}, vertex {r['vertex_ms']:.2f} / passes {r['passes_ms']:.2f} "
                     f"/ post {r['resolve_ms']:.2f}, memory {n(r['memory_bytes'])}, lost {r['lost']}, mismatched {r['mismatched_pixels']}"
                     for r in rows)


def main():
    d = Path(sys.argv[1])
    for name in ["all-bunny.json", "all-bunny-auto.json", "all-dragon.json"]:
        print(f"### {name}\n\n{render_table(records(d / name))}\n")
    for name in ["bench-bunny.json", "bench-dragon.json", "bench-bunny-spheres.json"]:
        print(f"### {name}\n\n{bench_table(records(d / name))}\n")
    print(f"### shipping\n\n{shipping_table(d)}\n")
    for name in sorted(d.glob("sweep-*.json")):
        print(sweep_summary(name) + "\n")
    for name in sorted(d.glob("sc-*.json")):
        print(bench_summary(name) + "\n")
    for name in ["done-abuffer.json", "bunny-spheres-abuffer8.json"]:
        for r in json.load(open(d / name)):
            print(f"- {name} {r['scheme']}: guarantee {r['guarantee']}, passes {r['passes']}, count pass "
                  f"{r['count_pass_ms']} ms, memory {n(r['memory_bytes'])}, captured {n(r['captured'])}, "
                  f"overflow {n(r['overflowed'])} (reported {n(r['reported_overflow'])}), lost {r['lost']}, "
                  f"verdict {'kept' if r['keeps_guarantee'] else 'BROKEN'}, time {r['time_ms']:.2f} ms")


main()

#!/usr/bin/env python3
"""Turns tools/device/cuda-captures.sh's log into the Markdown tables of docs/results-gpu.md."""
import json
import sys

# FreePipe (Liu et al., I3D 2010) Table 3: translucency at 512x512 on a GTX 280, 20 layers, fps.
FREEPIPE = {"bunny": {"mdts": 487, "abuffer": 614}, "dragon": {"mdts": 297, "abuffer": 363}}


def parse(path):
    scenes, gpu, cpu, cmp = {}, {}, {}, {}
    for line in open(path, errors="replace"):
        parts = line.rstrip("\n").split(" ", 2)
        if len(parts) >= 2 and parts[0].startswith("cmp-"):
            try:
                cmp[parts[0][4:]] = json.loads(line.split(" ", 1)[1])
            except ValueError:
                pass
            continue
        if len(parts) < 3:
            continue
        tag, kind, rest = parts
        try:
            data = json.loads(rest)
        except ValueError:
            continue
        if kind == "SCENE":
            scenes[tag] = data
        elif kind == "RESULT":
            gpu[(tag, data["scheme"])] = data
        elif kind == "CPU":
            for row in data:
                cpu[(tag, row["scheme"])] = row
    return scenes, gpu, cpu, cmp


def main():
    scenes, gpu, cpu, cmp = parse(sys.argv[1])
    print("### Verdicts (`fragsim compare oracle DUMP`)\n")
    print("| dump | equal | pixels equal | missing | extra | misordered | overflowed | fragments lost | extra |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, r in cmp.items():
        v, f = r["verdicts"], r["fragments"]
        print(f"| {name} | {'**yes**' if r['equal'] else '**NO**'} | {v['equal']} | {v['missing']} | {v['extra']} "
              f"| {v['misordered']} | {v['overflowed']} | {f['lost']} | {f['extra']} |")
    print("\n### Kernel times (median ms; frame = init + raster [+ sort])\n")
    head = ["scene", "triangles", "fragments", "max dc", "K", "GPU mdts", "GPU mdts32", "GPU abuffer (sort)",
            "GPU kbuffer (broken)", "CPU mdts", "CPU abuffer", "CPU/GPU mdts", "CPU/GPU abuffer",
            "GTX 280 mdts / abuffer", "GTX 280/GPU mdts", "GTX 280/GPU abuffer"]
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))

    def ms(t):
        return f"{t['frame_ms']:.3f}" if t else "–"

    def ratio(a, b):
        return f"{a / b:.3g}×" if a and b else "–"

    for tag, s in scenes.items():
        t = {scheme: gpu.get((tag, scheme), {}).get("timings")
             for scheme in ("mdts", "mdts32", "abuffer", "kbuffer")}
        base = tag.replace("-k20", "")
        cm, ca = cpu.get((base, "mdts")), cpu.get((base, "abuffer"))
        fp = FREEPIPE.get(tag.split("-")[0]) if tag.endswith("-512-k20") else None
        fp_m, fp_a = (1000 / fp["mdts"], 1000 / fp["abuffer"]) if fp else (None, None)
        gm = t["mdts"] and t["mdts"]["frame_ms"]
        ga = t["abuffer"] and t["abuffer"]["frame_ms"]
        cells = [tag, s["triangles"], s["fragments"], s["max_depth_complexity"], s["k"],
                 ms(t["mdts"]), ms(t["mdts32"]),
                 ms(t["abuffer"]) + (f" ({t['abuffer']['sort_ms']:.3f})" if t["abuffer"] else ""),
                 ms(t["kbuffer"]),
                 f"{cm['time_ms']:.2f} ({cm['threads']} thr)" if cm else "–",
                 f"{ca['time_ms']:.2f}" if ca else "–",
                 ratio(cm and cm["time_ms"], gm), ratio(ca and ca["time_ms"], ga),
                 f"{fp_m:.2f} / {fp_a:.2f}" if fp else "–", ratio(fp_m, gm), ratio(fp_a, ga)]
        print("| " + " | ".join(str(c) for c in cells) + " |")

if __name__ == "__main__":
    main()

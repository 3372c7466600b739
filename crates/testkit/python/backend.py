#!/usr/bin/env python3
"""A fragsim backend in plain Python, written from docs/dump-format.md and docs/semantics.md.

Usage: backend.py SCENE_DIR OUT_DIR [--bug BUG]

Reads the case `fragsim conform` wrote into SCENE_DIR (case.json, scene.tri: the triangle
export), scans every screen triangle with the top-left rule, interpolates depth in f64 and
rounds it once to f32, runs MDTS (`mdts`: FreePipe's atomicMin walk over K slots) or the fixed
A-buffer (`abuffer`: fetch-and-add, `capacity` slots), and writes the dump into OUT_DIR.
`--bug` plants a bug for `conform` to find:
  top-edge        a scan that misses pixel centres exactly on a top edge;
  third-fragment  an A-buffer whose 3rd fragment of a pixel is never written;
  early-break     an MDTS walk that stops one slot early;
  clamp-counters  an A-buffer whose counters stop at the capacity (counters = min(counters, C));
  deepest-third   an A-buffer that loses the 3rd fragment of its deepest pixel only;
  off-by-one      an A-buffer that stores while index <= C (the overflowing fragment lands in
                  the next pixel's first slot);
  racy-counter    an A-buffer whose counter is read and written back non-atomically: the
                  fragments run in waves of 32 in flight, each reads its pixel's counter before
                  any of the wave writes it back, so two of a wave at one pixel get one slot.
"""
import json, os, struct, sys

EMPTY = 0xFFFFFFFFFFFFFFFF
scene_dir, out_dir = sys.argv[1], sys.argv[2]
bug = sys.argv[4] if len(sys.argv) > 4 and sys.argv[3] == "--bug" else None
case = json.load(open(os.path.join(scene_dir, "case.json")))
data = open(os.path.join(scene_dir, "scene.tri"), "rb").read()
assert data[:8] == b"FRAGTRI1", "not a triangle export"
_, W, H, _, _, n, length, size = struct.unpack_from("<8I", data, 8)
scene = json.loads(data[40:40 + length])
records = 40 + (length + 7) // 8 * 8

def fragments():
    """Every (pixel, word) of the view, triangle by triangle (docs/semantics.md §4-6)."""
    for r in range(n):
        prim, x0, y0, x1, y1, x2, y2, _, z0, z1, z2 = struct.unpack_from("<I6iI3d", data, records + r * size)
        v, z = [(x0, y0), (x1, y1), (x2, y2)], [z0, z1, z2]
        area = (x1 - x0) * (y2 - y0) - (y1 - y0) * (x2 - x0)
        edges = [(v[1], v[2]), (v[2], v[0]), (v[0], v[1])]     # edge i is opposite vertex i
        lo = lambda c: max(0, -((128 - min(c)) // 256))         # first centre 256 i + 128 >= min
        hi = lambda c, side: min(side - 1, (max(c) - 128) // 256)
        for j in range(lo([y0, y1, y2]), hi([y0, y1, y2], H) + 1):
            for i in range(lo([x0, x1, x2]), hi([x0, x1, x2], W) + 1):
                px, py, e = 256 * i + 128, 256 * j + 128, []
                for (p, q) in edges:
                    ei = (q[0] - p[0]) * (py - p[1]) - (q[1] - p[1]) * (px - p[0])
                    dy, dx = q[1] - p[1], q[0] - p[0]
                    top, left = dy == 0 and dx > 0, dy < 0
                    if bug == "top-edge":
                        top = False
                    if ei < 0 or (ei == 0 and not (top or left)):
                        break
                    e.append(ei)
                else:
                    depth = (float(e[0]) * z[0] + float(e[1]) * z[1] + float(e[2]) * z[2]) / float(area)
                    f = struct.unpack("<f", struct.pack("<f", depth))[0]
                    if 0.0 <= f <= 1.0:
                        key = struct.unpack("<I", struct.pack("<f", f + 0.0))[0]   # -0.0 -> +0.0
                        yield j * W + i, key << 32 | prim

header = {"format": "fragsim-dump", "version": 1, "producer": "python backend.py", "scene": scene,
          "width": W, "height": H, "arrays": {}}
if case["scheme"] == "mdts":
    k = case["k"]
    slots = [EMPTY] * (W * H * k)
    for p, word in fragments():
        for s in range(k - 1 if bug == "early-break" else k):   # atomicMin walk, FreePipe §4.1
            old = slots[p * k + s]
            slots[p * k + s] = min(old, word)
            if old == EMPTY:
                break
            word = max(old, word)
    header.update(scheme="mdts", k=k)
    arrays = {"slots": ("u64", slots, [W * H, k])}
elif case["scheme"] == "abuffer":
    cap = case["capacity"]
    counters, slots = [0] * (W * H), [EMPTY] * (W * H * cap)
    stream = list(fragments())
    depth = [0] * (W * H)
    for p, _ in stream:
        depth[p] += 1
    deepest = depth.index(max(depth)) if stream else -1
    wave = 32 if bug == "racy-counter" else 1
    for start in range(0, len(stream), wave):
        batch = stream[start:start + wave]
        read = [counters[p] for p, _ in batch]                   # atomicAdd's read ...
        for (p, word), index in zip(batch, read):
            counters[p] = index + 1                              # ... and its write
            lost = (bug == "third-fragment" and index == 2) or \
                   (bug == "deepest-third" and p == deepest and index == 2)
            if (index <= cap if bug == "off-by-one" else index < cap) and not lost:
                slots[p * cap + index] = word
    if bug == "clamp-counters":
        counters = [min(c, cap) for c in counters]
    header.update(scheme="abuffer", capacity=cap, filled=True)
    arrays = {"counters": ("u32", counters, [W * H]), "slots": ("u64", slots, [W * H, cap])}
else:
    sys.exit("backend.py runs mdts and abuffer, not " + case["scheme"])
for name, (dtype, words, shape) in arrays.items():
    code = "<%d%s" % (len(words), "Q" if dtype == "u64" else "I")
    open(os.path.join(out_dir, name + "." + dtype), "wb").write(struct.pack(code, *words))
    header["arrays"][name] = {"file": name + "." + dtype, "dtype": dtype, "shape": shape}
json.dump(header, open(os.path.join(out_dir, "dump.json"), "w"))

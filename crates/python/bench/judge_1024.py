"""Judging a 1024 x 1024 capture from Python against `fragsim compare` on the same arrays.

    python crates/python/bench/judge_1024.py FRAGSIM_BINARY [REPEATS]

The capture is the exact MDTS capture (K = 8) of the bunny at 1024 x 1024, written as a dump
directory. Each repeat times, in turn and in this one process:
- `FRAGSIM compare oracle DIR --no-images` (a process: reads the dump, loads the scene, builds
  the oracle, judges);
- `fragsim.judge_dump(DIR)` (the same work in process: reads the dump, loads the scene, builds
  the oracle, judges);
- `fragsim.judge(Scene(...), ...)` on the arrays in memory with a new Scene (no files; the
  scene loaded and the oracle built);
- `fragsim.judge(scene, ...)` on a Scene that keeps its oracle (what a test suite judging many
  captures of one scene pays after the first).
It prints each one's minimum and median wall time and their ratios to `compare`'s.
"""

import statistics
import subprocess
import sys
import tempfile
import time

import fragsim

BINARY = sys.argv[1]
REPEATS = int(sys.argv[2]) if len(sys.argv) > 2 else 5
K = 8


def scene():
    return fragsim.Scene("bunny", width=1024, height=1024, view=30, elevation=15)


kept = scene()
slots = kept.reference(K).nearest
directory = tempfile.mkdtemp(prefix="fragsim-bench-")
fragsim.write_dump(directory, kept, "mdts", {"slots": slots}, k=K)
assert fragsim.judge(kept, "mdts", {"slots": slots}, k=K).equal


def compare():
    done = subprocess.run([BINARY, "compare", "oracle", directory, "--no-images"], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


def judge_dump():
    assert fragsim.judge_dump(directory).equal


def judge_new_scene():
    assert fragsim.judge(scene(), "mdts", {"slots": slots}, k=K).equal


def judge_kept_scene():
    assert fragsim.judge(kept, "mdts", {"slots": slots}, k=K).equal


runs = {"fragsim compare": compare, "judge_dump": judge_dump, "judge, new Scene": judge_new_scene, "judge, Scene kept": judge_kept_scene}
times = {name: [] for name in runs}
for _ in range(REPEATS):
    for name, run in runs.items():
        start = time.perf_counter()
        run()
        times[name].append(time.perf_counter() - start)
base = min(times["fragsim compare"])
print(f"bunny 1024x1024, MDTS K={K}, {int(kept.reference().counts.sum())} fragments, {REPEATS} repeats each, interleaved")
for name, t in times.items():
    print(f"{name:20s} min {min(t) * 1e3:8.1f} ms  median {statistics.median(t) * 1e3:8.1f} ms  min/compare's {min(t) / base:.2f}")

"""fragsim's Python package judging captures made on a CUDA GPU: CuPy raw kernels (an A-buffer
by atomicAdd counters, MDTS by atomicMin on u64 words, a linked list by an atomicAdd allocator
and atomicExch heads) and PyTorch's scatter_reduce(amin) on packed depth|id words, each plain and
with a planted bug (a lost fragment, a non-atomic read-modify-write, a wrong id).

    python3 gpu_clients.py [SCENE] [WIDTH] [HEIGHT]

Run by tools/device/python-gpu.sh on the device machine; prints one line per capture: the
kernel, the verdict, the differing pixels, the first one named, and the time of the judgement.
"""

import sys
import time

import cupy as cp
import numpy as np
import torch

import fragsim

SCENE, WIDTH, HEIGHT = (sys.argv[1:] + ["bunny", "1024", "1024"][len(sys.argv) - 1 :])[:3]
scene = fragsim.Scene(SCENE, width=int(WIDTH), height=int(HEIGHT), view=30, elevation=15)
frags = scene.fragments()
ref = scene.reference()
n = len(frags)
depth_complexity = int(ref.counts.max())
lists = cp.asarray(frags.list)
words = cp.asarray(frags.word)

SOURCE = r"""
extern "C" __global__ void abuffer(const unsigned *lists, const unsigned long long *words,
                                   unsigned *counters, unsigned long long *slots,
                                   int capacity, int n, int lost) {
    int i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n || i == lost) return;
    unsigned p = lists[i];
    unsigned c = atomicAdd(&counters[p], 1u);
    if (c < (unsigned)capacity) slots[(size_t)p * capacity + c] = words[i];
}

extern "C" __global__ void mdts(const unsigned *lists, const unsigned long long *words,
                                unsigned long long *slots, int k, int n, int plant) {
    int i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    unsigned p = lists[i];
    unsigned long long w = words[i];
    for (int s = 0; s < k; ++s) {
        unsigned long long *slot = &slots[(size_t)p * k + s];
        unsigned long long old;
        if (plant) {            // the planted bug: a load and a store, not one atomicMin
            old = *(volatile unsigned long long *)slot;
            if (w < old) *(volatile unsigned long long *)slot = w;
        } else {
            old = atomicMin(slot, w);
        }
        if (old == 0xFFFFFFFFFFFFFFFFull) break;
        w = old > w ? old : w;
    }
}

extern "C" __global__ void linked_list(const unsigned *lists, const unsigned long long *words,
                                       unsigned *counter, unsigned *heads, unsigned *next,
                                       unsigned long long *nodes, unsigned pool, int n,
                                       int wrong) {
    int i = blockIdx.x * blockDim.x + threadIdx.x;
    if (i >= n) return;
    unsigned node = atomicAdd(counter, 1u) + 1u;
    if (node <= pool) {
        unsigned old = atomicExch(&heads[lists[i]], node);
        unsigned long long w = words[i];
        if (i == wrong) w += 1;  // the planted bug: the next primitive's id
        nodes[node - 1] = w;
        next[node - 1] = old;
    }
}
"""
module = cp.RawModule(code=SOURCE)
BLOCK = 256
GRID = (n + BLOCK - 1) // BLOCK


def launch(name, *args):
    module.get_function(name)((GRID,), (BLOCK,), args)
    cp.cuda.Device().synchronize()


def empty(count):
    return cp.full(count, fragsim.EMPTY64, dtype=cp.uint64)


def report(kernel, scheme, arrays, expect_pixel=None, **layout):
    start = time.perf_counter()
    verdict = fragsim.judge(scene, scheme, arrays, **layout)
    took = time.perf_counter() - start
    first = verdict.examples[0] if verdict.examples else None
    named = "" if first is None else f"; first pixel {first['pixel']} (x {first['x']}, y {first['y']}): {', '.join(first['verdict'])}"
    check = ""
    if expect_pixel is not None:
        check = f"; planted at pixel {expect_pixel}: {'named' if expect_pixel in verdict.pixel.tolist() else 'NOT NAMED'}"
    print(f"{kernel:38s} {verdict.word:24s} differing {verdict.mismatched:7d}{named}{check}; judged in {took * 1e3:.0f} ms", flush=True)
    return verdict


print(f"device {torch.cuda.get_device_name()}, CuPy {cp.__version__}, PyTorch {torch.__version__}, fragsim {fragsim.__version__}")
print(f"scene {SCENE} {WIDTH}x{HEIGHT}: {n} fragments, max depth complexity {depth_complexity}")

# A-buffer: atomicAdd counters hand out slots; the plant drops one fragment.
for lost in (-1, n // 2):
    counters = cp.zeros(scene.lists, dtype=cp.uint32)
    slots = empty(scene.lists * depth_complexity)
    launch("abuffer", lists, words, counters, slots, np.int32(depth_complexity), np.int32(n), np.int32(lost))
    name = "cupy abuffer (atomicAdd)" if lost < 0 else "cupy abuffer, a lost fragment"
    report(name, "abuffer", {"counters": counters, "slots": slots}, None if lost < 0 else int(frags.list[lost]),
           capacity=depth_complexity, filled=True)

# MDTS: atomicMin walks on u64 words; the plant is a non-atomic read-modify-write.
for k in (1, 8):
    for plant in (0, 1):
        slots = empty(scene.lists * k)
        launch("mdts", lists, words, slots, np.int32(k), np.int32(n), np.int32(plant))
        name = f"cupy mdts K={k} (atomicMin u64)" if not plant else f"cupy mdts K={k}, non-atomic min"
        report(name, "mdts", {"slots": slots}, k=k)

# Linked list: atomicAdd allocator, atomicExch heads; the plant names the wrong primitive.
for wrong in (-1, 17):
    counter = cp.zeros(1, dtype=cp.uint32)
    heads = cp.zeros(scene.lists, dtype=cp.uint32)
    nxt = cp.zeros(n, dtype=cp.uint32)
    nodes = empty(n)
    launch("linked_list", lists, words, counter, heads, nxt, nodes, np.uint32(n), np.int32(n), np.int32(wrong))
    name = "cupy linked list (atomicAdd, atomicExch)" if wrong < 0 else "cupy linked list, a wrong id"
    report(name, "linked-list", {"heads": heads, "next": nxt, "nodes": nodes, "counter": counter},
           None if wrong < 0 else int(frags.list[wrong]), k=depth_complexity, pool=n)

# PyTorch: scatter_reduce amin on packed words (the visibility buffer), judged as K = 1.
t_lists = torch.from_numpy(frags.list.astype(np.int64)).cuda()
t_words = torch.from_numpy(frags.word.view(np.int64).copy()).cuda()
none = torch.iinfo(torch.int64).max
for reduce in ("amin", "amax"):
    out = torch.full((scene.lists,), none if reduce == "amin" else -1, dtype=torch.int64, device="cuda")
    out.scatter_reduce_(0, t_lists, t_words, reduce=reduce, include_self=reduce == "amin")
    out[out == none] = -1
    torch.cuda.synchronize()
    report(f"torch scatter_reduce {reduce} (CUDA)", "mdts", {"slots": out}, k=1)

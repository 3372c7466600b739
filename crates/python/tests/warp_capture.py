"""Capture kernels written in NVIDIA Warp as a Warp user writes them, one thread per fragment
(a fragment-shader invocation), fed with fragsim's fragment stream (``Scene.fragments()``):

- ``abuffer``: FreePipe's A-buffer, an ``atomic_add`` counter per pixel handing out slots;
- ``mdts``: the K nearest by MDTS insertion, ``atomic_min`` walks on u64 ``depth|id`` words;
- ``linked_list``: per-pixel linked lists, a global ``atomic_add`` allocator and ``atomic_exch``
  heads;
- ``kbuffer_racy``: the k-buffer's read-modify-write of a pixel's K slots (load K, insert, store
  K) without a lock: correct one fragment at a time, wrong when two fragments of a pixel run
  together.

Warp runs a kernel's threads on its CPU device one after another, so a race between two
fragments never happens there. The kernels that race (``kbuffer_racy`` and the planted
non-atomic MDTS walk) are therefore launched under the most adversarial lockstep schedule: every
fragment's loads in one launch, then every fragment's stores in the next, so each thread reads
before any thread writes (as a GPU warp does within itself). Two fragments of one pixel then
read the same slots and the later store wins: exactly the pixels with two fragments or more lose
fragments. The atomic kernels need no such care: an atomic is one step, whatever the schedule.

Each capture can carry a planted bug (``plant=``), and the tests check that fragsim names the
pixel it damages: a lost fragment (A-buffer), a non-atomic read-modify-write (MDTS), a wrong
primitive id (linked list).
"""

from __future__ import annotations

import numpy as np
import warp as wp

import fragsim

wp.config.quiet = True
DEVICE = "cpu"
EMPTY = wp.constant(wp.uint64(0xFFFFFFFFFFFFFFFF))


@wp.kernel
def abuffer_kernel(
    lists: wp.array(dtype=wp.uint32),
    words: wp.array(dtype=wp.uint64),
    counters: wp.array(dtype=wp.uint32),
    slots: wp.array(dtype=wp.uint64),
    capacity: int,
    lost: int,
):
    i = wp.tid()
    if i == lost:  # the planted bug: this fragment never reaches memory
        return
    p = int(lists[i])
    n = int(wp.atomic_add(counters, p, wp.uint32(1)))
    if n < capacity:
        slots[p * capacity + n] = words[i]


@wp.kernel
def mdts_kernel(
    lists: wp.array(dtype=wp.uint32),
    words: wp.array(dtype=wp.uint64),
    slots: wp.array(dtype=wp.uint64),
    k: int,
):
    i = wp.tid()
    p = int(lists[i])
    w = words[i]
    for s in range(k):
        old = wp.atomic_min(slots, p * k + s, w)
        if old == EMPTY:
            break
        w = wp.max(old, w)  # carry the farther word on to the next slot


@wp.kernel
def mdts_load(
    lists: wp.array(dtype=wp.uint32),
    carried: wp.array(dtype=wp.uint64),
    slots: wp.array(dtype=wp.uint64),
    seen: wp.array(dtype=wp.uint64),
    s: int,
    k: int,
):
    i = wp.tid()
    if carried[i] != EMPTY:
        seen[i] = slots[int(lists[i]) * k + s]


@wp.kernel
def mdts_store(
    lists: wp.array(dtype=wp.uint32),
    carried: wp.array(dtype=wp.uint64),
    slots: wp.array(dtype=wp.uint64),
    seen: wp.array(dtype=wp.uint64),
    s: int,
    k: int,
):
    # The planted bug: min(slot, w) as a load (mdts_load) and a store, not one atomic_min.
    i = wp.tid()
    w = carried[i]
    if w == EMPTY:
        return
    old = seen[i]
    if w < old:
        slots[int(lists[i]) * k + s] = w
    if old == EMPTY:
        carried[i] = EMPTY
    else:
        carried[i] = wp.max(old, w)


@wp.kernel
def linked_list_kernel(
    lists: wp.array(dtype=wp.uint32),
    words: wp.array(dtype=wp.uint64),
    counter: wp.array(dtype=wp.uint32),
    heads: wp.array(dtype=wp.uint32),
    next_: wp.array(dtype=wp.uint32),
    nodes: wp.array(dtype=wp.uint64),
    pool: int,
    wrong: int,
):
    i = wp.tid()
    n = wp.atomic_add(counter, 0, wp.uint32(1)) + wp.uint32(1)
    if int(n) <= pool:
        old = wp.atomic_exch(heads, int(lists[i]), n)
        w = words[i]
        if i == wrong:  # the planted bug: the node names the next primitive
            w = w + wp.uint64(1)
        nodes[int(n) - 1] = w
        next_[int(n) - 1] = old


@wp.kernel
def kbuffer_load(
    lists: wp.array(dtype=wp.uint32),
    slots: wp.array(dtype=wp.uint64),
    local: wp.array2d(dtype=wp.uint64),
    k: int,
):
    i = wp.tid()
    p = int(lists[i])
    for s in range(k):
        local[i, s] = slots[p * k + s]


@wp.kernel
def kbuffer_insert_store(
    lists: wp.array(dtype=wp.uint32),
    words: wp.array(dtype=wp.uint64),
    slots: wp.array(dtype=wp.uint64),
    local: wp.array2d(dtype=wp.uint64),
    k: int,
):
    i = wp.tid()
    p = int(lists[i])
    w = words[i]
    for s in range(k):  # insertion into the sorted copy, then every slot written back
        old = local[i, s]
        if w < old:
            local[i, s] = w
            w = old
    for s in range(k):
        slots[p * k + s] = local[i, s]


def _inputs(scene: fragsim.Scene) -> tuple[wp.array, wp.array, int]:
    f = scene.fragments()
    lists = wp.array(f.list, dtype=wp.uint32, device=DEVICE)
    words = wp.array(f.word, dtype=wp.uint64, device=DEVICE)
    return lists, words, len(f)


def _empty_slots(n: int) -> wp.array:
    return wp.array(np.full(n, fragsim.EMPTY64, dtype=np.uint64), dtype=wp.uint64, device=DEVICE)


def abuffer(scene: fragsim.Scene, capacity: int, lost: int = -1) -> dict[str, wp.array]:
    """The A-buffer's counters and slots (filled with the empty marker first)."""
    lists, words, n = _inputs(scene)
    counters = wp.zeros(scene.lists, dtype=wp.uint32, device=DEVICE)
    slots = _empty_slots(scene.lists * capacity)
    if n:
        wp.launch(abuffer_kernel, dim=n, inputs=[lists, words, counters, slots, capacity, lost], device=DEVICE)
    return {"counters": counters, "slots": slots}


def mdts(scene: fragsim.Scene, k: int, plant: bool = False) -> dict[str, wp.array]:
    """MDTS's K slots per pixel; with ``plant``, each step's ``atomic_min`` split into a load and
    a store, run in lockstep."""
    lists, words, n = _inputs(scene)
    slots = _empty_slots(scene.lists * k)
    if n and not plant:
        wp.launch(mdts_kernel, dim=n, inputs=[lists, words, slots, k], device=DEVICE)
    elif n:
        carried = wp.clone(words)
        seen = wp.zeros(n, dtype=wp.uint64, device=DEVICE)
        for s in range(k):
            args = [lists, carried, slots, seen, s, k]
            wp.launch(mdts_load, dim=n, inputs=args, device=DEVICE)
            wp.launch(mdts_store, dim=n, inputs=args, device=DEVICE)
    return {"slots": slots}


def linked_list(scene: fragsim.Scene, pool: int, wrong: int = -1) -> dict[str, wp.array]:
    """Per-pixel linked lists: heads, next links, nodes and the allocator's counter (fragsim's
    numbering: node n at index n - 1, 0 ends a list)."""
    lists, words, n = _inputs(scene)
    counter = wp.zeros(1, dtype=wp.uint32, device=DEVICE)
    heads = wp.zeros(scene.lists, dtype=wp.uint32, device=DEVICE)
    next_ = wp.zeros(pool, dtype=wp.uint32, device=DEVICE)
    nodes = _empty_slots(pool)
    if n:
        args = [lists, words, counter, heads, next_, nodes, pool, wrong]
        wp.launch(linked_list_kernel, dim=n, inputs=args, device=DEVICE)
    return {"heads": heads, "next": next_, "nodes": nodes, "counter": counter}


def kbuffer_racy(scene: fragsim.Scene, k: int) -> dict[str, wp.array]:
    """The k-buffer's unlocked read-modify-write, in lockstep."""
    lists, words, n = _inputs(scene)
    slots = _empty_slots(scene.lists * k)
    if n:
        local = wp.zeros((n, max(k, 1)), dtype=wp.uint64, device=DEVICE)
        wp.launch(kbuffer_load, dim=n, inputs=[lists, slots, local, k], device=DEVICE)
        wp.launch(kbuffer_insert_store, dim=n, inputs=[lists, words, slots, local, k], device=DEVICE)
    return {"slots": slots}

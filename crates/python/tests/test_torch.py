"""A second framework: PyTorch's ``scatter_reduce`` with ``amin`` on packed ``depth|id`` words,
the visibility-buffer pattern (one nearest fragment a pixel), judged as MDTS with K = 1.

PyTorch is not installed by CI (PyPI's wheel brings the CUDA libraries, gigabytes): without it
these tests skip, saying so; the device runs the same pattern on CUDA (docs/results-gpu.md)."""

import numpy as np
import pytest

import fragsim

torch = pytest.importorskip("torch", reason="PyTorch is not installed: the scatter_reduce client is skipped")

SCENE = fragsim.Scene("spheres:3", width=48, height=36, view=30, elevation=15)
#: The empty pixel before the reduction: int64's largest (every packed word is below it).
NONE = torch.iinfo(torch.int64).max


def visibility_buffer(scene, prims_plus=0):
    f = scene.fragments()
    words = torch.from_numpy(f.word.view(np.int64).copy()) + prims_plus
    lists = torch.from_numpy(f.list.astype(np.int64))
    out = torch.full((scene.lists,), NONE, dtype=torch.int64)
    out.scatter_reduce_(0, lists, words, reduce="amin", include_self=True)
    out[out == NONE] = -1  # all ones as u64: MDTS's empty slot
    return out


def test_scatter_reduce_amin_is_equal_as_k1():
    verdict = fragsim.judge(SCENE, "mdts", {"slots": visibility_buffer(SCENE)}, k=1)
    assert verdict.word == "EQUAL (bit-identical)"


def test_scatter_reduce_amax_is_named():
    f = SCENE.fragments()
    words = torch.from_numpy(f.word.view(np.int64).copy())
    out = torch.full((SCENE.lists,), -1, dtype=torch.int64)
    out.scatter_reduce_(0, torch.from_numpy(f.list.astype(np.int64)), words, reduce="amax", include_self=False)
    verdict = fragsim.judge(SCENE, "mdts", {"slots": out}, k=1)
    assert not verdict.equal
    assert np.array_equal(verdict.differing, np.flatnonzero(SCENE.reference().counts >= 2))

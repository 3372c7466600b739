"""Warp kernels (warp_capture.py) judged by fragsim: each capture EQUAL, each planted bug
DIFFERENT with the pixel it damages named, and the racy k-buffer shrunk by the battery."""

import numpy as np
import pytest

import fragsim
import warp_capture as wc
from fragsim.testing import assert_conforms, assert_equal, run_battery

# Three nested spheres: up to 6 fragments a pixel.
SCENE = fragsim.Scene("spheres:3", width=48, height=36, view=30, elevation=15)
DEPTH_COMPLEXITY = int(SCENE.reference().counts.max())


def test_the_scene_has_pixels_of_several_fragments():
    assert DEPTH_COMPLEXITY == 6


def test_abuffer_is_equal():
    arrays = wc.abuffer(SCENE, DEPTH_COMPLEXITY)
    verdict = assert_equal(SCENE, "abuffer", arrays, capacity=DEPTH_COMPLEXITY, filled=True)
    assert verdict.word == "EQUAL (bit-identical)"
    assert verdict.fragments["captured"] == len(SCENE.fragments())


def test_abuffer_below_the_depth_complexity_overflows_as_predicted():
    capacity = 2
    verdict = assert_equal(SCENE, "abuffer", wc.abuffer(SCENE, capacity), capacity=capacity, filled=True)
    counts = SCENE.reference().counts.astype(np.int64)
    assert verdict.fragments["overflowed"] == int(np.maximum(counts - capacity, 0).sum()) > 0


def test_abuffer_lost_fragment_is_named():
    fragments = SCENE.fragments()
    lost = len(fragments) // 2
    pixel = int(fragments.list[lost])
    arrays = wc.abuffer(SCENE, DEPTH_COMPLEXITY, lost=lost)
    verdict = fragsim.judge(SCENE, "abuffer", arrays, capacity=DEPTH_COMPLEXITY, filled=True)
    assert not verdict.equal
    assert verdict.pixel.tolist() == [pixel]
    assert verdict.fragments["lost"] == 1
    with pytest.raises(AssertionError, match=f"pixel {pixel} \\(x {pixel % 48}, y {pixel // 48}\\): missing"):
        assert_equal(SCENE, "abuffer", arrays, capacity=DEPTH_COMPLEXITY, filled=True)


@pytest.mark.parametrize("k", [1, 4, DEPTH_COMPLEXITY])
def test_mdts_atomic_min_walk_is_equal(k):
    assert_equal(SCENE, "mdts", wc.mdts(SCENE, k), k=k)


def test_mdts_holds_the_reference_k_nearest():
    k = 3
    slots = wc.mdts(SCENE, k)["slots"].numpy().reshape(SCENE.lists, k)
    assert np.array_equal(slots, SCENE.reference(k).nearest)


def test_mdts_non_atomic_read_modify_write_is_named():
    k = 4
    verdict = fragsim.judge(SCENE, "mdts", wc.mdts(SCENE, k, plant=True), k=k)
    assert not verdict.equal
    # Under lockstep every pixel of two fragments or more keeps one: exactly those differ.
    counts = SCENE.reference().counts
    assert np.array_equal(verdict.differing, np.flatnonzero(counts >= 2))
    first = int(verdict.differing[0])
    with pytest.raises(AssertionError, match=f"pixel {first} \\(x {first % 48}, y {first // 48}\\): missing"):
        assert_equal(SCENE, "mdts", wc.mdts(SCENE, k, plant=True), k=k)


def test_linked_list_is_equal():
    pool = len(SCENE.fragments())
    verdict = assert_equal(SCENE, "linked-list", wc.linked_list(SCENE, pool), k=DEPTH_COMPLEXITY, pool=pool)
    assert verdict.words["unreachable"] == 0


def test_linked_list_wrong_id_is_named():
    fragments = SCENE.fragments()
    pool = len(fragments)
    wrong = 17
    pixel = int(fragments.list[wrong])
    arrays = wc.linked_list(SCENE, pool, wrong=wrong)
    verdict = fragsim.judge(SCENE, "linked-list", arrays, k=DEPTH_COMPLEXITY, pool=pool)
    assert not verdict.equal
    assert verdict.pixel.tolist() == [pixel]
    (example,) = verdict.examples
    assert {e["prim"] for e in example["candidate"]} ^ {e["prim"] for e in example["reference"]} == {
        int(fragments.prim[wrong]),
        int(fragments.prim[wrong]) + 1,
    }


def test_kbuffer_racy_is_named_on_every_pixel_of_two_fragments():
    k = 4
    verdict = fragsim.judge(SCENE, "kbuffer", wc.kbuffer_racy(SCENE, k), k=k)
    assert np.array_equal(verdict.differing, np.flatnonzero(SCENE.reference().counts >= 2))


def _warp_backend(kernel):
    def backend(scene, scheme, k, capacity):
        return kernel(scene, k), {"k": k}

    backend.__name__ = kernel.__name__
    return backend


def test_the_battery_passes_the_atomic_mdts_walk():
    result = assert_conforms(_warp_backend(wc.mdts), "mdts", k=3, cases=24)
    assert result.cases == 24 and result.claim == "exact"


def test_the_battery_shrinks_the_racy_kbuffer():
    result = run_battery(_warp_backend(wc.kbuffer_racy), "kbuffer", k=2, claim="exact", cases=24)
    assert not result.passed
    print(result.describe())
    # Two fragments in one pixel are the least that races: the battery finds that case.
    assert len(result.triangles) == 2
    assert result.width * result.height <= 2
    assert result.mismatches and result.property in ("equal", "order-independent")


def test_the_battery_refuses_a_claim_the_kbuffer_does_not_make():
    with pytest.raises(fragsim.BatteryRefused, match="owes no exact capture"):
        run_battery(_warp_backend(wc.kbuffer_racy), "kbuffer", k=2, cases=4)

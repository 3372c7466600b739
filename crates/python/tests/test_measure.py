"""fragsim's measurements from Python (the ``fragsim_measure`` crate): the k-buffer's hazard on a
scene, as ``fragsim hazard`` measures it."""

import pytest

import fragsim

# Six quads stacked in depth: every covered pixel has several fragments to race for K slots.
QUADS = fragsim.Scene("quads:6", width=24, height=24)


def test_hazard_is_zero_alone_and_loses_fragments_with_many_threads_in_flight():
    report = QUADS.hazard(k=8, threads_in_flight=(1, 4096), seeds=2)
    ref = QUADS.reference()
    assert report["fragments"] == len(ref.words)
    assert report["covered"] == int((ref.counts > 0).sum())
    assert sum(n for _, n in report["buckets"]) == report["covered"]
    rows = report["rows"]
    # Two machines × two policies × two widths.
    assert len(rows) == 8
    for row in rows:
        assert len(row["mismatched_pixel_rate_per_seed"]) == 2
        assert row["mismatched_pixel_rate"] == pytest.approx(sum(row["mismatched_pixel_rate_per_seed"]) / 2)
        if row["threads_in_flight"] == 1:
            # One walk at a time: no read is ever stale, nothing is lost.
            assert (row["mismatched_pixel_rate"], row["lost"]) == (0, 0), row
    wide = [r for r in rows if r["threads_in_flight"] == 4096 and r["policy"] == "random"]
    assert {r["write_back"] for r in wide} == {"render-target", "separate-stores"}
    for row in wide:
        assert row["mismatched_pixel_rate"] > 0 and row["lost"] > 0, row
    # Stale reads lose; only torn write-backs duplicate.
    assert all(r["duplicates"] == 0 for r in rows if r["write_back"] == "render-target")


def test_hazard_refuses_an_unknown_machine():
    with pytest.raises(fragsim.FragsimError, match="no k-buffer machine"):
        QUADS.hazard(write_back=("register-file",))

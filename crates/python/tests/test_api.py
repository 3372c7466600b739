"""The package's API on fragsim's own captures: scenes, the reference, judging, typed errors,
dump directories."""

import json
import os

import numpy as np
import pytest

import fragsim

SCENE = fragsim.Scene("spheres:2", width=32, height=24, view=30, elevation=15)


def test_version():
    assert fragsim.__version__.count(".") == 2


def test_reference_lists_are_sorted_and_counted():
    ref = SCENE.reference(k=2)
    assert ref.counts.shape == (32 * 24,)
    assert int(ref.offsets[-1]) == len(ref.words) == int(ref.counts.sum()) == len(SCENE.fragments())
    p = int(np.argmax(ref.counts))
    assert list(ref.list(p)) == sorted(ref.list(p))
    assert list(ref.nearest[p]) == list(ref.list(p)[:2])
    assert np.all(ref.nearest[ref.counts == 0] == fragsim.EMPTY64)
    assert np.all((ref.depths >= 0) & (ref.depths <= 1))


def test_fragments_are_the_reference_in_submission_order():
    f = SCENE.fragments()
    ref = SCENE.reference()
    assert sorted(f.word.tolist()) == sorted(ref.words.tolist())
    assert np.array_equal(f.word, fragsim.pack(f.depth, f.prim))


def test_triangles_export():
    t = SCENE.triangles()
    assert t.xy.shape == (len(t.prim), 3, 2) and t.z.shape == (len(t.prim), 3)
    assert t.prim.max() < SCENE.mesh_triangles


def test_exact_reference_is_equal_and_a_changed_word_differs():
    k = 4
    slots = SCENE.reference(k).nearest.copy()
    assert fragsim.judge(SCENE, "mdts", {"slots": slots}, k=k).word == "EQUAL (bit-identical)"
    p = int(np.flatnonzero(SCENE.reference().counts)[0])
    slots[p, 0] += 1  # the nearest fragment names the next primitive
    verdict = fragsim.judge(SCENE, "mdts", {"slots": slots}, k=k)
    assert verdict.word == "DIFFERENT" and verdict.pixel.tolist() == [p]
    assert verdict.x.tolist() == [p % 32] and verdict.y.tolist() == [p // 32]
    assert "missing" in verdict.examples[0]["verdict"]
    assert f"pixel {p} (x {p % 32}, y {p // 32})" in verdict.report()
    assert json.loads(verdict.json)["mismatched_pixels"] == 1


def test_signed_and_shaped_arrays_are_taken_bit_for_bit():
    k = 3
    slots = SCENE.reference(k).nearest
    as_int64 = slots.view(np.int64).reshape(24, 32, k)
    assert fragsim.judge(SCENE, "mdts", {"slots": as_int64}, k=k).equal


def test_slot_major_layout():
    k = 3
    slots = np.ascontiguousarray(SCENE.reference(k).nearest.T)
    layout = {"kind": "slots", "order": "slot-major"}
    assert fragsim.judge(SCENE, "mdts", {"slots": slots}, k=k, layout=layout).equal


def test_misspelt_field_is_a_dump_error_naming_it():
    with pytest.raises(fragsim.DumpError, match="unknown field `capacty`"):
        fragsim.judge(SCENE, "abuffer", {"slots": np.zeros(4, np.uint64)}, capacty=4)


def test_wrong_shape_is_a_dump_error_naming_the_array_and_field():
    with pytest.raises(fragsim.DumpError, match='array "slots": shape \\[768, 3\\] disagrees with the header\'s "k" 4'):
        fragsim.judge(SCENE, "mdts", {"slots": SCENE.reference(3).nearest}, k=4)


def test_float_array_is_a_dump_error():
    with pytest.raises(fragsim.DumpError, match="dtype float32"):
        fragsim.judge(SCENE, "mdts", {"slots": np.zeros((768, 1), np.float32)}, k=1)


def test_unknown_scheme_is_a_dump_error():
    with pytest.raises(fragsim.DumpError, match="mdtz"):
        fragsim.judge(SCENE, "mdtz", {"slots": SCENE.reference(1).nearest}, k=1)


def test_errors_share_a_base():
    assert issubclass(fragsim.DumpIoError, fragsim.DumpError)
    for e in (fragsim.DumpError, fragsim.SceneError, fragsim.JudgeError, fragsim.BatteryRefused):
        assert issubclass(e, fragsim.FragsimError)


def test_bad_scenes_are_scene_errors():
    with pytest.raises(fragsim.SceneError, match="nonesuch"):
        fragsim.Scene("nonesuch")
    with pytest.raises(fragsim.SceneError, match="width"):
        fragsim.Scene("spheres:1", width=0)
    with pytest.raises(fragsim.SceneError, match="exactly one"):
        fragsim.Scene()
    with pytest.raises(fragsim.SceneError, match="index"):
        fragsim.Scene(vertices=np.zeros((3, 3)), indices=[[0, 1, 7]])
    with pytest.raises(fragsim.SceneError, match="window_origin|upper-right"):
        fragsim.Scene("spheres:1", window_origin="upper-right")


def quad_scene(**conventions):
    # Two triangles at depth 0.25 and one at 0.75 behind, in normalised device coordinates.
    vertices = np.array(
        [[-1, -1, 0.25], [1, -1, 0.25], [1, 1, 0.25], [-1, -1, 0.25], [1, 1, 0.25], [-1, 1, 0.25],
         [-0.5, -0.5, 0.75], [0.5, -0.5, 0.75], [0, 0.5, 0.75]],
        dtype=np.float32,
    )
    indices = np.arange(9).reshape(3, 3)
    return fragsim.Scene(vertices=vertices, indices=indices, width=16, height=8, view_projection=np.eye(4), **conventions)


def test_array_scene_under_an_engine_matrix():
    scene = quad_scene()
    ref = scene.reference()
    assert ref.counts.min() == 1 and ref.counts.max() == 2
    assert set(np.unique(ref.depths).tolist()) == {np.float32(0.25), np.float32(0.75)}


def test_lower_left_origin_keeps_the_picture_rows():
    # The arrays keep row 0 at the top of the picture whatever the window origin: an OpenGL
    # capture of the same picture is judged against the same lists.
    upper, lower = quad_scene().reference(), quad_scene(window_origin="lower-left").reference()
    assert np.array_equal(upper.counts, lower.counts)
    assert quad_scene(window_origin="lower-left").spec["conventions"]["window_origin"] == "lower-left"


def test_samples_make_lists_per_sample():
    scene = fragsim.Scene("spheres:1", width=8, height=6, samples=4)
    assert scene.lists == 8 * 6 * 4
    ref = scene.reference(2)
    verdict = fragsim.judge(scene, "mdts", {"slots": ref.nearest}, k=2)
    assert verdict.equal and verdict.lists_per_pixel == 4


def test_write_read_and_judge_a_dump(tmp_path):
    scene = quad_scene()
    k = 2
    fragsim.write_dump(tmp_path / "d", scene, "mdts", {"slots": scene.reference(k).nearest}, k=k)
    assert sorted(os.listdir(tmp_path / "d")) == ["dump.json", "mesh.obj", "slots.u64"]
    dump = fragsim.read_dump(tmp_path / "d")
    assert dump.header["k"] == 2 and dump.arrays["slots"].shape == (128, 2)
    assert fragsim.judge_dump(tmp_path / "d").equal
    again = fragsim.Scene.from_dump(tmp_path / "d")
    assert np.array_equal(again.reference().words, scene.reference().words)


def test_reading_a_missing_dump_is_a_dump_io_error(tmp_path):
    with pytest.raises(fragsim.DumpIoError, match="cannot read"):
        fragsim.read_dump(tmp_path / "nothing")


def test_a_verdict_is_no_truth_value():
    verdict = fragsim.judge(SCENE, "mdts", {"slots": SCENE.reference(1).nearest}, k=1)
    with pytest.raises(TypeError):
        bool(verdict)


def test_f32_vertex_precision_judges_within_bounds():
    scene = fragsim.Scene("spheres:2", width=32, height=24, view=30, elevation=15, vertex_precision="f32")
    slots = scene.reference(4).nearest
    verdict = fragsim.judge(scene, "mdts", {"slots": slots}, k=4, vertex_precision="f32")
    assert verdict.equal and "f32 vertex stage" in verdict.compared

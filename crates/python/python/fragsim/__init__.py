"""fragsim: judge a GPU kernel's multi-fragment buffers against fragsim's exact oracle, in memory.

A kernel that captures every fragment of a pixel (an A-buffer), the K nearest (MDTS's
``atomicMin`` walk, a k-buffer) or a linked list leaves arrays in memory. This package hands
those arrays, as numpy arrays or anything numpy can take (CuPy, PyTorch and Warp arrays are
copied to the host), to fragsim's oracle and returns its verdict, the one ``fragsim compare``
prints, without a dump directory:

>>> import fragsim
>>> scene = fragsim.Scene("spheres:2", width=32, height=24, view=30, elevation=15)
>>> ref = scene.reference(k=4)
>>> fragsim.judge(scene, "mdts", {"slots": ref.nearest}, k=4).equal
True

The pieces: :class:`Scene` (a named scene, a mesh file or vertex and index arrays, seen through
the orbit camera or an engine's ``view_projection``, under the conventions of a dump header), its
:meth:`Scene.triangles` (the screen triangles after fragsim's vertex stage), :meth:`Scene.fragments`
(the fragment stream a fragment shader would see), :meth:`Scene.reference` (the exact per-pixel
lists), :func:`judge` (a :class:`Verdict`), :func:`write_dump` and :func:`read_dump` (dump
directories, ``docs/dump-format.md``), and :mod:`fragsim.testing` (a pytest assertion and the
conformance battery over a Python callable).

Errors are typed: :class:`DumpError` (arrays or a header that contradict the dump format;
:class:`DumpIoError` for files), :class:`SceneError`, :class:`JudgeError`,
:class:`BatteryRefused`, all :class:`FragsimError`.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Mapping, Optional, Sequence

import numpy as np

from . import _fragsim
from ._fragsim import (
    BatteryRefused,
    DumpError,
    DumpIoError,
    FragsimError,
    JudgeError,
    SceneError,
    __version__,
)

__all__ = [
    "__version__",
    "Scene",
    "Triangles",
    "Fragments",
    "Reference",
    "Verdict",
    "Dump",
    "judge",
    "judge_dump",
    "write_dump",
    "read_dump",
    "to_host",
    "pack",
    "FLAGS",
    "SCHEMES",
    "EMPTY32",
    "EMPTY64",
    "FragsimError",
    "DumpError",
    "DumpIoError",
    "SceneError",
    "JudgeError",
    "BatteryRefused",
]

#: The empty marker of a u64 slot (MDTS, the A-buffer when filled): all ones.
EMPTY64 = 0xFFFF_FFFF_FFFF_FFFF
#: The empty marker of a u32 slot: all ones.
EMPTY32 = 0xFFFF_FFFF
#: The verdict flags of a list by name; ``FLAGS["differs"]`` holds those that make it differ.
FLAGS: dict[str, int] = dict(_fragsim.verdict_flags())
#: Every scheme of fragsim's catalog, as a dump header names it.
SCHEMES: tuple[str, ...] = tuple(_fragsim.scheme_names())

_FORMAT = "fragsim-dump"
_VERSION = 1


def to_host(array: Any) -> np.ndarray:
    """The array as a numpy array on the host: CuPy (``.get()``), PyTorch (``.cpu().numpy()``)
    and Warp (``.numpy()``) arrays are copied from their device, anything else goes through
    ``numpy.asarray``."""
    if isinstance(array, np.ndarray):
        return array
    module = type(array).__module__.split(".")[0]
    if module == "cupy":
        return array.get()
    if module == "torch":
        return array.detach().cpu().numpy()
    if module == "warp":
        return array.numpy()
    return np.asarray(array)


def pack(keys: Any, prims: Any) -> np.ndarray:
    """fragsim's fragment words ``key << 32 | prim`` (uint64) from depth keys and primitive ids;
    ``keys`` may be float32 depths (their bits are the keys) or uint32 keys."""
    keys = np.asarray(to_host(keys))
    if keys.dtype == np.float32:
        keys = (keys + np.float32(0.0)).view(np.uint32)  # -0.0 + 0.0 is +0.0
    return (keys.astype(np.uint64) << np.uint64(32)) | np.asarray(to_host(prims)).astype(np.uint64)


def _words(name: str, array: Any) -> np.ndarray:
    """An array as little-endian u32 or u64 words: signed integers are taken bit for bit."""
    try:
        a = np.ascontiguousarray(to_host(array))
    except Exception as e:  # noqa: BLE001 - any conversion failure is a bad array
        raise DumpError(f"array {name!r}: cannot be read as an array ({e})") from e
    if a.dtype.kind not in "ui" or a.dtype.itemsize not in (4, 8):
        raise DumpError(
            f"array {name!r}: dtype {a.dtype} is not a 32- or 64-bit integer "
            "(u32 counters and links, u32 or u64 slot and node words)"
        )
    unsigned = np.dtype(f"<u{a.dtype.itemsize}")
    return a.astype(a.dtype.newbyteorder("<"), copy=False).view(unsigned)


def _encode(
    scene: "Scene", scheme: str, arrays: Mapping[str, Any], layout: Mapping[str, Any]
) -> tuple[str, dict[str, bytes]]:
    """The dump header (``dump.json``'s JSON) and the arrays' bytes by file name."""
    header: dict[str, Any] = {
        "format": _FORMAT,
        "version": _VERSION,
        "producer": "fragsim Python " + __version__,
        "scene": scene.spec,
        "width": scene.width,
        "height": scene.height,
        "scheme": scheme,
        "arrays": {},
    }
    # Every layout field is passed through: the header's parser refuses an unknown one by name.
    header.update({k: v for k, v in layout.items() if v is not None})
    files: dict[str, bytes] = {}
    for name, array in arrays.items():
        words = _words(name, array)
        dtype = "u32" if words.dtype.itemsize == 4 else "u64"
        file = f"{name}.{dtype}"
        header["arrays"][name] = {"file": file, "dtype": dtype, "shape": list(words.shape) or [1]}
        files[file] = words.tobytes()
    return json.dumps(header), files


@dataclass(frozen=True)
class Triangles:
    """The screen triangles after fragsim's vertex stage (transform, clipping, snapping,
    orientation), as ``fragsim export-scene`` writes them: scanning each under fragsim's rules
    gives exactly the scene's fragments."""

    #: Primitive id of each piece (uint32 ``[n]``); a clipped triangle gives several pieces.
    prim: np.ndarray
    #: Vertex positions in 1/256 pixel, y down (int32 ``[n, 3, 2]``).
    xy: np.ndarray
    #: Window depth of each vertex (float64 ``[n, 3]``).
    z: np.ndarray


@dataclass(frozen=True)
class Fragments:
    """The scene's fragments in submission order, one per fragment-shader invocation."""

    #: The list each lands in: pixel ``y * width + x`` (``pixel * samples + s`` per sample).
    list: np.ndarray
    #: Depth keys: the f32 depth's bits (uint32).
    key: np.ndarray
    #: Primitive ids (uint32).
    prim: np.ndarray

    @property
    def depth(self) -> np.ndarray:
        """The depths (float32)."""
        return self.key.view(np.float32)

    @property
    def word(self) -> np.ndarray:
        """fragsim's fragment words ``key << 32 | prim`` (uint64): MDTS's ``atomicMin`` operand."""
        return pack(self.key, self.prim)

    def __len__(self) -> int:
        return len(self.key)


@dataclass(frozen=True)
class Reference:
    """The exact reference: every list's fragments in canonical order (depth key, then
    primitive id)."""

    #: Fragments per list (uint32 ``[lists]``): the depth complexity.
    counts: np.ndarray
    #: Where each list starts in ``words`` (uint64 ``[lists + 1]``).
    offsets: np.ndarray
    #: Every list's fragment words ``key << 32 | prim``, list after list (uint64).
    words: np.ndarray
    #: With a K: the K nearest of each list (uint64 ``[lists, K]``, empty slots ``EMPTY64``),
    #: what an MDTS capture holds.
    nearest: Optional[np.ndarray] = None

    def list(self, index: int) -> np.ndarray:
        """List ``index``'s fragment words."""
        return self.words[int(self.offsets[index]) : int(self.offsets[index + 1])]

    @property
    def depths(self) -> np.ndarray:
        """Every fragment's depth (float32), in ``words`` order."""
        return (self.words >> np.uint64(32)).astype(np.uint32).view(np.float32)

    @property
    def prims(self) -> np.ndarray:
        """Every fragment's primitive id (uint32), in ``words`` order."""
        return (self.words & np.uint64(0xFFFF_FFFF)).astype(np.uint32)


class Scene:
    """A scene on a viewport: what a capture is judged against.

    Name it as a dump header does: a named scene (``"bunny"``, ``"spheres:8"``,
    ``"soup:2000:1"``, ``"quads:8"``), a mesh file (``mesh="horse.ply"``, OBJ or PLY), or
    ``vertices`` (``[n, 3]`` floats) and ``indices`` (``[m, 3]`` integers). The camera is the
    orbit (``view``, ``elevation`` in degrees, ``fov_y``, ``distance_scale``, around the ``up``
    axis) or an engine's ``view_projection`` (4 × 4, row-major: ``clip = M @ (x, y, z, 1)``;
    ``matrix_precision="f32"`` rounds each entry to f32 as a GPU uniform holds it). The
    conventions are a dump header's: ``window_origin`` (``"upper-left"``, ``"lower-left"``),
    ``depth_range`` (``"zero-to-one"``, ``"minus-one-to-one"``), ``vertex_precision``
    (``"f64"``, ``"f32"``), ``subpixel_bits`` (1 to 8), ``samples`` (1, 2, 4, 8, 16) and
    ``edge_ties`` (``"top-left"``, …; ``None``: undeclared).

    The oracle is built on first use and kept, so judging many captures of one scene pays for
    it once.

    Raises :class:`SceneError` for a scene that cannot be loaded or viewed.
    """

    def __init__(
        self,
        name: Optional[str] = None,
        *,
        mesh: Optional[str | os.PathLike[str]] = None,
        vertices: Any = None,
        indices: Any = None,
        width: int = 256,
        height: int = 256,
        view: float = 0.0,
        elevation: float = 0.0,
        fov_y: float = 40.0,
        distance_scale: float = 1.1,
        up: str = "y",
        view_projection: Any = None,
        matrix_precision: str = "f64",
        window_origin: str = "upper-left",
        depth_range: str = "zero-to-one",
        vertex_precision: str = "f64",
        subpixel_bits: int = 8,
        samples: int = 1,
        edge_ties: Optional[str] = None,
    ) -> None:
        given = sum(x is not None for x in (name, mesh, vertices))
        if given != 1:
            raise SceneError("name a scene, a mesh file or vertex arrays: exactly one of them")
        spec: dict[str, Any] = {
            "view_degrees": float(view),
            "elevation_degrees": float(elevation),
            "fov_y_degrees": float(fov_y),
            "distance_scale": float(distance_scale),
        }
        if name is not None:
            spec["name"] = name
        if mesh is not None:
            spec["mesh"] = os.fspath(mesh)
        if view_projection is not None:
            matrix = np.asarray(to_host(view_projection), dtype=np.float64)
            if matrix.shape not in ((4, 4), (16,)):
                raise SceneError(f"view_projection must be 4 × 4, not {matrix.shape}")
            spec["view_projection"] = {
                "row_major": [float(v) for v in matrix.reshape(16)],
                "precision": matrix_precision,
            }
        conventions: dict[str, Any] = {
            "window_origin": window_origin,
            "subpixel_bits": int(subpixel_bits),
            "depth_range": depth_range,
            "vertex_precision": vertex_precision,
            "samples": int(samples),
        }
        if edge_ties is not None:
            conventions["edge_ties"] = edge_ties
        spec["conventions"] = conventions
        if vertices is not None:
            if indices is None:
                raise SceneError("vertices need their indices ([m, 3] integers)")
            v = np.ascontiguousarray(to_host(vertices), dtype=np.float32)
            i = np.asarray(to_host(indices))
            if i.dtype.kind not in "ui" or (i.size and (i.min() < 0 or i.max() > EMPTY32)):
                raise SceneError("indices must be non-negative integers below 2^32")
            i = np.ascontiguousarray(i, dtype=np.uint32)
            self._core = _fragsim.SceneCore(json.dumps(spec), width, height, up, v, i)
        elif indices is not None:
            raise SceneError("indices need their vertices ([n, 3] floats)")
        else:
            self._core = _fragsim.SceneCore(json.dumps(spec), width, height, up)

    @classmethod
    def from_spec(
        cls,
        spec: Mapping[str, Any],
        width: int,
        height: int,
        beside: Optional[str | os.PathLike[str]] = None,
    ) -> "Scene":
        """The scene a dump header's ``scene`` object names, on ``width`` × ``height`` pixels; a
        relative mesh path is looked up in the working directory, then in ``beside``."""
        beside = None if beside is None else os.fspath(beside)
        return cls._wrap(_fragsim.SceneCore(json.dumps(dict(spec)), width, height, "y", None, None, beside))

    @classmethod
    def from_dump(cls, path: str | os.PathLike[str]) -> "Scene":
        """The scene a dump directory (or its ``dump.json``) names."""
        dump = read_dump(path)
        return cls.from_spec(dump.header["scene"], dump.header["width"], dump.header["height"], dump.directory)

    @classmethod
    def _wrap(cls, core: Any) -> "Scene":
        scene = cls.__new__(cls)
        scene._core = core
        return scene

    @property
    def spec(self) -> dict[str, Any]:
        """The scene object a dump header records (an array scene names ``mesh.obj``, written
        beside each of its dumps, and its hash)."""
        return json.loads(self._core.spec_json())

    @property
    def width(self) -> int:
        """Viewport width in pixels."""
        return self._core.width

    @property
    def height(self) -> int:
        """Viewport height in pixels."""
        return self._core.height

    @property
    def samples(self) -> int:
        """Samples a pixel."""
        return self._core.samples

    @property
    def lists(self) -> int:
        """Lists a capture holds: one per pixel, or per sample when ``samples`` > 1."""
        return self.width * self.height * self.samples

    @property
    def mesh_triangles(self) -> int:
        """Triangles in the mesh: primitive ids are below this."""
        return self._core.mesh_triangles

    def triangles(self) -> Triangles:
        """The screen triangles after fragsim's vertex stage (``export-scene``'s content)."""
        return Triangles(**self._core.triangles())

    def fragments(self) -> Fragments:
        """The fragments in submission order, as a fragment shader would be invoked: feed them to
        a capture kernel to test its atomics without a rasterizer of its own."""
        return Fragments(**self._core.fragments())

    def reference(self, k: Optional[int] = None) -> Reference:
        """The exact per-list fragments; with ``k``, also the K nearest of each list."""
        return Reference(**self._core.reference(k))

    def hazard(
        self,
        k: int = 8,
        threads_in_flight: Sequence[int] = (1, 32, 1024),
        seeds: int = 3,
        write_back: Sequence[str] = ("render-target", "separate-stores"),
    ) -> dict[str, Any]:
        """The k-buffer's read-modify-write hazard on this scene, as ``fragsim hazard`` measures
        it: for each machine of ``write_back`` (``"render-target"``: write-backs committed in
        order, only a stale read loses; ``"separate-stores"``: K loads and K stores, as CUDA code
        does), each scheduling policy (``"random"``, ``"warps"``) and each number of threads in
        flight ``W``, the k-buffer with ``k`` slots runs under the scheduled executor for
        ``seeds`` seeds. Returns the report: ``covered``, ``fragments``, ``buckets`` and one
        dict per row in ``rows`` (``write_back``, ``policy``, ``threads_in_flight``,
        ``mismatched_pixel_rate`` and its ``_per_seed`` list, ``lost``, ``extra``,
        ``duplicates``, ``misordered_pixels``, ``mismatched_pixel_rate_by_depth_complexity``).
        ``W = 1`` runs each walk alone: its rate is 0.

        Raises :class:`FragsimError` for an unknown machine, no seed or ``W = 0``.
        """
        report = self._core.hazard(int(k), [int(w) for w in threads_in_flight], int(seeds), list(write_back))
        return json.loads(report)

    def __repr__(self) -> str:
        spec = self.spec
        what = spec.get("name") or spec.get("mesh")
        return f"Scene({what!r}, width={self.width}, height={self.height}, samples={self.samples})"


class Verdict:
    """The oracle's verdict on a capture: what ``fragsim compare oracle DUMP`` reports.

    ``equal`` is the decision; ``word`` says it in words (``EQUAL (bit-identical)``,
    ``EQUAL (within tolerance)``, ``DIFFERENT``, …). The differing lists are numpy arrays
    (:attr:`differing`, :attr:`x`, :attr:`y`, :attr:`sample`, :attr:`differing_flags`), the
    totals dicts (:attr:`counts`, :attr:`fragments`, :attr:`words`), the first differing lists
    with both sides :attr:`examples`, the qualifications :attr:`notes`, what to check next
    :attr:`hints`; :meth:`report` is the text, :attr:`json` the summary as ``compare``'s JSON
    groups it.
    """

    def __init__(self, raw: Mapping[str, Any]) -> None:
        self.equal: bool = bool(raw["equal"])
        self.word: str = raw["word"]
        self.json: str = raw["summary"]
        self.summary: dict[str, Any] = json.loads(raw["summary"])
        #: Per list, the verdict's flags (uint8, :data:`FLAGS`).
        self.flags: np.ndarray = raw["flags"]
        #: Per list, the fragments the reference holds (uint32).
        self.reference_fragments: np.ndarray = raw["reference_fragments"]
        self.width: int = raw["width"]
        self.height: int = raw["height"]
        self.lists_per_pixel: int = raw["lists_per_pixel"]

    def __bool__(self) -> bool:
        raise TypeError("a Verdict is not a truth value: use verdict.equal")

    @property
    def counts(self) -> dict[str, int]:
        """Lists per verdict: ``equal``, ``missing``, ``extra``, ``misordered``,
        ``overflowed``, ``overflow-miscounted``, ``corrupt``, ``within-precision``,
        ``ambiguous``."""
        return self.summary["verdicts"]

    @property
    def fragments(self) -> dict[str, int]:
        """Fragment totals: ``reference``, ``captured``, ``lost``, ``extra``, ``overflowed``,
        ``overflow_claimed``."""
        return self.summary["fragments"]

    @property
    def words(self) -> dict[str, Any]:
        """Word totals of the storage: ``checked``, ``corrupt``, ``unchecked`` (words a header
        could have defined but did not), ``spare`` (room no counter handed out: a linked list's
        pool past its counter), ``unreachable``."""
        return self.summary["words"]

    @property
    def compared(self) -> str:
        """What was compared, in words."""
        return self.summary["compared"]

    @property
    def notes(self) -> list[str]:
        """Notes that qualify the verdict."""
        return self.summary["notes"]

    @property
    def hints(self) -> list[str]:
        """What to check next, where the differences have a shape that names a cause (the
        whole frame, depth rounding only, edges only); never a change to the verdict."""
        return self.summary["hints"]

    @property
    def examples(self) -> list[dict[str, Any]]:
        """The first differing lists, both sides: ``pixel``, ``x``, ``y``, ``verdict`` (flag
        names), ``reference`` and ``candidate`` (lists of ``{key, depth, prim}``)."""
        return self.summary["first_differences"]

    @property
    def differing(self) -> np.ndarray:
        """Indices of the differing lists (pixels, or samples ``pixel * samples + s``)."""
        return np.flatnonzero(self.flags & FLAGS["differs"])

    @property
    def mismatched(self) -> int:
        """How many lists differ."""
        return int(self.summary["mismatched_pixels"])

    @property
    def differing_flags(self) -> np.ndarray:
        """The flags of each differing list."""
        return self.flags[self.differing]

    @property
    def pixel(self) -> np.ndarray:
        """The pixel of each differing list."""
        return self.differing // self.lists_per_pixel

    @property
    def x(self) -> np.ndarray:
        """The column of each differing list's pixel."""
        return self.pixel % self.width

    @property
    def y(self) -> np.ndarray:
        """The row of each differing list's pixel (row 0 at the top)."""
        return self.pixel // self.width

    @property
    def sample(self) -> np.ndarray:
        """The sample of each differing list (0 at one sample a pixel)."""
        return self.differing % self.lists_per_pixel

    def report(self) -> str:
        """The verdict as text: counts, totals, notes, hints and the first differing lists."""
        s = self.summary
        v = s["verdicts"]
        f = s["fragments"]
        lines = [
            f"verdict: {self.word}",
            f"compared: {s['compared']}",
            f"lists {s['pixels']}: "
            + ", ".join(f"{name} {v[name]}" for name in v if v[name] or name == "equal"),
            (
                f"fragments: reference {f['reference']}, captured {f['captured']}, lost {f['lost']}, "
                f"extra {f['extra']}, overflowed by design {f['overflowed']}"
                + (
                    ""
                    if f["overflow_claimed"] == f["overflowed"]
                    else f" (counters claim {f['overflow_claimed']})"
                )
            ),
        ]
        if s["words"]["checked"]:
            w = s["words"]
            lines.append(
                f"words: corrupt {w['corrupt']}, not checked {w['unchecked']}, "
                f"spare room not read {w['spare']}, nodes no list reaches {w['unreachable']}"
            )
        lines += [f"note: {n}" for n in s["notes"]]
        lines += [f"hint: {h}" for h in s["hints"]]
        lines += [_describe_example(e) for e in self.examples]
        return "\n".join(lines)

    def __repr__(self) -> str:
        return f"<Verdict {self.word}: {self.mismatched} of {self.summary['pixels']} lists differ>"


def _entry(e: Mapping[str, Any]) -> str:
    prim = e.get("prim")
    return f"{e['depth']:.9g}" + ("" if prim is None else f" prim {prim}")


def _describe_example(e: Mapping[str, Any]) -> str:
    """One differing list: where, why, expected and found."""
    where = f"pixel {e['pixel']} (x {e['x']}, y {e['y']}" + (
        f", sample {e['sample']})" if "sample" in e else ")"
    )
    expected = ", ".join(_entry(x) for x in e["reference"]) or "nothing"
    found = ", ".join(_entry(x) for x in e["candidate"]) or "nothing"
    text = f"{where}: {', '.join(e['verdict'])}\n  expected: {expected}\n  found:    {found}"
    for c in e.get("corrupt_words", []):
        text += f"\n  slot {c['slot']}: {c['word']} {c['why']}"
    return text


def judge(
    scene: Scene,
    scheme: str,
    arrays: Mapping[str, Any],
    *,
    vertex_precision: str = "f64",
    depth_ulps: int = 0,
    examples: int = 8,
    **layout: Any,
) -> Verdict:
    """The oracle's verdict on ``arrays``, a capture of ``scene`` by ``scheme``.

    ``scheme`` and ``arrays`` are a dump's (``docs/dump-format.md``): ``"mdts"`` with
    ``{"slots": [lists, k] u64}``, ``"abuffer"`` with ``counters`` and ``slots``,
    ``"linked-list"`` with ``heads``, ``next``, ``nodes`` and ``counter``, and so on. The
    keyword arguments are the dump header's layout fields: ``k``, ``capacity``, ``sorted``,
    ``filled``, ``pool``, ``layers``, ``layout`` (a dict: slot order, list numbering, payload
    word), ``word``, ``producer``, ``extra``; a misspelt one is refused by name.
    ``vertex_precision="f32"`` judges a GPU vertex stage within the bounds derived for f32,
    ``depth_ulps`` accepts depth keys within that many ulps, ``examples`` keeps that many
    differing lists with both sides.

    Raises :class:`DumpError` for arrays or fields that contradict the format (naming them),
    :class:`JudgeError` when the sides cannot be compared.
    """
    header, files = _encode(scene, scheme, arrays, layout)
    return Verdict(scene._core.judge(header, files, vertex_precision, depth_ulps, examples))


@dataclass(frozen=True)
class Dump:
    """A dump read from a directory: its header (``dump.json`` as a dict) and its arrays,
    shaped as the header says."""

    header: dict[str, Any]
    arrays: dict[str, np.ndarray]
    #: The directory it was read from.
    directory: str

    @property
    def layout(self) -> dict[str, Any]:
        """The header's layout fields, as :func:`judge` and :func:`write_dump` take them."""
        skip = {"format", "version", "scene", "width", "height", "scheme", "arrays"}
        return {k: v for k, v in self.header.items() if k not in skip}


def write_dump(
    path: str | os.PathLike[str], scene: Scene, scheme: str, arrays: Mapping[str, Any], **layout: Any
) -> None:
    """Writes ``arrays`` as a dump directory at ``path`` (``dump.json`` and one file per array),
    for ``fragsim compare oracle PATH``; an array scene's mesh goes beside it as ``mesh.obj``.
    The keyword arguments are :func:`judge`'s layout fields."""
    header, files = _encode(scene, scheme, arrays, layout)
    scene._core.write_dump(os.fspath(path), header, files)


def read_dump(path: str | os.PathLike[str]) -> Dump:
    """Reads a dump directory (or its ``dump.json``), every check of ``fragsim compare``
    included."""
    header_json, flat = _fragsim.read_dump(os.fspath(path))
    header = json.loads(header_json)
    arrays = {
        name: words.reshape([int(d) for d in header["arrays"][name]["shape"]])
        for name, words in flat.items()
    }
    path = os.fspath(path)
    directory = path if os.path.isdir(path) else (os.path.dirname(path) or ".")
    return Dump(header, arrays, directory)


def judge_dump(
    path: str | os.PathLike[str],
    *,
    vertex_precision: str = "f64",
    depth_ulps: int = 0,
    examples: int = 8,
) -> Verdict:
    """The verdict on a dump directory (or its ``dump.json``) against the oracle of the scene it
    names: what ``fragsim compare oracle PATH`` decides, the dump read once, in Rust."""
    path = os.fspath(path)
    directory = path if os.path.isdir(path) else (os.path.dirname(path) or ".")
    header_path = os.path.join(directory, "dump.json") if os.path.isdir(path) else path
    try:
        with open(header_path, "rb") as f:
            header = json.loads(f.read())
    except OSError as e:
        raise DumpIoError(f"cannot read {header_path}: {e.strerror}") from e
    except ValueError as e:
        raise DumpError(f"{header_path}: {e}") from e
    scene = Scene.from_spec(header["scene"], header["width"], header["height"], directory)
    return Verdict(scene._core.judge_dir(path, vertex_precision, depth_ulps, examples))

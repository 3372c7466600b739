"""fragsim for test suites: an assertion for pytest, and the conformance battery over a Python
callable.

:func:`assert_equal` judges a capture and, when it differs, fails with a message that names the
first differing pixels, what the oracle expected there and what the capture held.

:func:`run_battery` and :func:`assert_conforms` run fragsim's conformance battery (the testkit's
generated cases, the verdict ``fragsim compare`` gives, and on a failure the case shrunk by
proptest and the battery's own crop to a few triangles and pixels) on a backend written in
Python: a callable ``backend(scene, scheme, k, capacity)`` that captures ``scene`` (a
:class:`fragsim.Scene`; its :meth:`~fragsim.Scene.fragments` or
:meth:`~fragsim.Scene.triangles` feed the kernel) and returns its arrays, or its arrays and the
dump header's layout fields, as :func:`fragsim.judge` takes them::

    def backend(scene, scheme, k, capacity):
        slots = my_kernel(scene.fragments(), scene.lists, k)
        return {"slots": slots}, {"k": k}

    fragsim.testing.assert_conforms(backend, "mdts", k=4)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Optional, Union

from . import Scene, Verdict, _encode, _fragsim, judge

__all__ = ["assert_equal", "failure_message", "run_battery", "assert_conforms", "BatteryResult", "Backend"]

#: A backend under the battery: ``backend(scene, scheme, k, capacity)`` returns the arrays, or
#: ``(arrays, layout)`` with the dump header's layout fields.
Backend = Callable[[Scene, str, int, int], Union[Mapping[str, Any], tuple]]


def failure_message(verdict: Verdict, scheme: str, show: int = 4) -> str:
    """Why a verdict is not equal, in a few lines: the counts, then the first ``show``
    differing pixels with the fragments expected and found."""
    c = verdict.counts
    kinds = ", ".join(
        f"{name} {c[name]}"
        for name in ("missing", "extra", "misordered", "overflow-miscounted", "corrupt")
        if c.get(name)
    )
    lines = [
        f"{scheme} capture {verdict.word}: {verdict.mismatched} of {verdict.summary['pixels']} "
        f"lists differ ({kinds})"
    ]
    from . import _describe_example

    lines += [_describe_example(e) for e in verdict.examples[:show]]
    lines += [f"note: {n}" for n in verdict.notes]
    return "\n".join(lines)


def assert_equal(
    scene: Scene, scheme: str, arrays: Mapping[str, Any], *, show: int = 4, **options: Any
) -> Verdict:
    """Asserts that ``arrays`` (a capture of ``scene`` by ``scheme``) is equal to the oracle, as
    :func:`fragsim.judge` decides (``options`` are its keyword arguments); returns the verdict.

    Raises ``AssertionError`` naming the first ``show`` differing pixels, expected and found."""
    verdict = judge(scene, scheme, arrays, examples=max(show, 1), **options)
    if not verdict.equal:
        raise AssertionError(failure_message(verdict, scheme, show))
    return verdict


@dataclass(frozen=True)
class BatteryResult:
    """What the battery found: ``passed`` with the ``cases`` checked and the ``claim``, or the
    shrunk counterexample."""

    passed: bool
    cases: int = 0
    claim: str = ""
    #: The property broken: ``runs``, ``equal``, ``order-independent`` or ``overflow``.
    property: str = ""
    message: str = ""
    #: The shrunk case's viewport.
    width: int = 0
    height: int = 0
    #: Its triangles as submitted: corners in half pixels, depths.
    triangles: list = field(default_factory=list)
    #: Its mesh as OBJ text (identity view-projection: x, y are normalised device coordinates).
    obj: str = ""
    #: The first differing pixels: ``pixel``, ``x``, ``y``, ``expected``, ``found`` (words).
    mismatches: list = field(default_factory=list)
    fragments: int = 0
    cases_run: int = 0
    case_number: int = 0
    shrink_steps: int = 0

    def describe(self) -> str:
        """The result in a few lines."""
        if self.passed:
            return f"passed: {self.cases} cases, claim {self.claim}"
        lines = [
            f"{self.property}: {self.message}",
            f"shrunk to {len(self.triangles)} triangles on {self.width}x{self.height} pixels "
            f"(case {self.case_number}, {self.shrink_steps} shrinking steps)",
        ]
        for t in self.triangles:
            lines.append(f"  triangle corners {t['corners_half_pixels']} (half pixels), depths {t['depths']}")
        for m in self.mismatches:
            lines.append(
                f"  pixel {m['pixel']} (x {m['x']}, y {m['y']}): expected "
                f"{[hex(w) for w in m['expected']]}, found {[hex(w) for w in m['found']]}"
            )
        return "\n".join(lines)


def _adapter(backend: Backend) -> Callable[[Any, str, int, int], tuple[str, dict[str, bytes]]]:
    """The callable the native battery calls: the case's scene in, a dump's header and bytes
    out."""

    def call(core: Any, scheme: str, k: int, capacity: int) -> tuple[str, dict[str, bytes]]:
        scene = Scene._wrap(core)
        out = backend(scene, scheme, k, capacity)
        arrays, layout = out if isinstance(out, tuple) else (out, {})
        return _encode(scene, scheme, arrays, layout)

    return call


def run_battery(
    backend: Backend,
    scheme: str,
    *,
    k: int = 4,
    capacity: int = 8,
    cases: int = 64,
    seed: int = 0,
    claim: Optional[str] = None,
    vertex_precision: str = "f64",
    max_side: int = 8,
    max_triangles: int = 6,
    shrink_steps: int = 2048,
    name: Optional[str] = None,
) -> BatteryResult:
    """Runs the conformance battery on ``backend`` for catalog scheme ``scheme`` at ``k`` and
    ``capacity``: ``cases`` generated cases from ``seed`` (at most ``max_side`` pixels a side,
    ``max_triangles`` triangles), checking ``claim`` (``"exact"``, ``"exact-within-capacity"``;
    default the scheme's own guarantee). A failing case is shrunk (at most ``shrink_steps``
    backend runs).

    Raises :class:`fragsim.BatteryRefused` when nothing can be checked."""
    raw = _fragsim.run_battery(
        _adapter(backend),
        scheme,
        k,
        capacity,
        name or getattr(backend, "__name__", "a Python backend"),
        cases,
        seed,
        claim,
        vertex_precision,
        max_side,
        max_triangles,
        shrink_steps,
    )
    return BatteryResult(**raw)


def assert_conforms(backend: Backend, scheme: str, **options: Any) -> BatteryResult:
    """Asserts that ``backend`` passes the battery (``options`` are :func:`run_battery`'s);
    raises ``AssertionError`` with the shrunk counterexample."""
    result = run_battery(backend, scheme, **options)
    if not result.passed:
        raise AssertionError(result.describe())
    return result

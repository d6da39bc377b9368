"""Compiled kernels: how long compiling took, and compiling them ahead of time.

regopack's kernels are compiled by numba on first use and cached on disk
(see :mod:`regopack.jit`). :func:`compile_timer` measures the compilation that
happens inside a block, from numba's own compile events, so that a run can
report its insertion time without it. :func:`compile_kernels` (the command
``regopack compile``) packs, analyses and exports a few tiny scenes that use
every built-in kernel, which fills the cache, e.g. when building a cluster
image.
"""

from __future__ import annotations

import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["CompileTime", "compile_kernels", "compile_timer"]

TINY: dict[str, Any] = {"domain.width": 60.0, "domain.height": 60.0, "count": 60}
"""Overrides that make the ``small`` scene tiny (a fraction of a second once compiled)."""

VARIANTS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("polygons in a walled rectangle", {}),
    ("a circle", {"domain": {"kind": "circle", "radius": 30.0}}),
    (
        "a convex polygon",
        {"domain": {"kind": "polygon", "vertices": [[-30, -30], [30, -30], [30, 30], [-30, 20]]}},
    ),
    (
        "a periodic rectangle",
        {"domain.kind": "periodic", "domain.width": 80.0, "domain.height": 80.0},
    ),
    ("disks among polygons", {"phases.0.shape": {"kind": "disk"}}),
    (
        "disks in a periodic rectangle",
        {
            "phases.0.shape": {"kind": "disk"},
            "domain.kind": "periodic",
            "domain.width": 80.0,
            "domain.height": 80.0,
        },
    ),
    (
        "disks in a circle",
        {"phases.0.shape": {"kind": "disk"}, "domain": {"kind": "circle", "radius": 30.0}},
    ),
    (
        "disks in a convex polygon",
        {
            "phases.0.shape": {"kind": "disk"},
            "domain": {"kind": "polygon", "vertices": [[-30, -30], [30, -30], [30, 30], [-30, 20]]},
        },
    ),
    ("the sweep order", {"insertion.order": "sweep"}),
    (
        "disks among polygons, the sweep order",
        {"insertion.order": "sweep", "phases.0.shape": {"kind": "disk"}},
    ),
    (
        "polyhedra in a box (3D)",
        {
            "domain.kind": "box",
            "domain.depth": 60.0,
            "domain.center": [0.0, 0.0, 0.0],
            "phases": [{"name": "glass", "fraction": 1.0, "shape": {"kind": "polyhedron"}}],
            "insertion": {"kind": "available-surface"},
            "count": 12,
        },
    ),
    ("exact refusals", {"insertion.screening": "exact"}),
    ("random sequential addition", {"insertion": {"kind": "rsa"}}),
)
"""Scenes :func:`compile_kernels` packs: ``small`` made tiny, then changed by these fields."""


@dataclass
class CompileTime:
    """Seconds spent compiling inside a :func:`compile_timer` block.

    Another thread (a helper of the insertion) may compile while the thread that
    opened the block goes on working, so the two are told apart.

    Attributes
    ----------
    seconds
        Wall time during which any thread compiled (nested compilations counted once).
    functions
        Number of compilations (each kernel signature compiled, nested ones included).
    own_seconds
        Wall time during which the thread that opened the block compiled; the rest
        of that thread's time is its own work, including waits for the compiler
        while another thread holds it.
    """

    seconds: float = 0.0
    functions: int = 0
    own_seconds: float = 0.0
    _owner: int = field(default_factory=threading.get_ident, repr=False, compare=False)
    _depth: dict[int, int] = field(default_factory=dict, repr=False, compare=False)
    _start: dict[int, float] = field(default_factory=dict, repr=False, compare=False)
    _busy: int = field(default=0, repr=False, compare=False)
    _since: float = field(default=0.0, repr=False, compare=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)

    @property
    def elsewhere(self) -> bool:
        """Whether some compilation ran on another thread than the block's."""
        return self.seconds > self.own_seconds

    def run_times(self, wall: float) -> dict[str, Any]:
        """Return a run summary's timing fields for a block of ``wall`` seconds so far.

        The insertion time leaves out only the opening thread's compilations (a helper
        compiling meanwhile does not stop it); a note says when another thread compiled.
        """
        times: dict[str, Any] = {
            "wall_time_s": wall,
            "insertion_time_s": max(wall - self.own_seconds, 0.0),
            "compile_time_s": self.seconds,
        }
        if self.elsewhere:
            times["insertion_time_note"] = (
                "another thread compiled kernels during the insertion, which may have waited"
                " for it or gone on without its help: time a second run for the usual figure"
            )
        return times

    def _event(self, event: Any) -> None:
        me = threading.get_ident()
        now = time.perf_counter()
        with self._lock:
            depth = self._depth.get(me, 0)
            if event.is_start:
                if depth == 0:
                    self._start[me] = now
                    if self._busy == 0:
                        self._since = now
                    self._busy += 1
                self._depth[me] = depth + 1
                self.functions += 1
            elif depth > 0:
                self._depth[me] = depth - 1
                if depth == 1:
                    if me == self._owner:
                        self.own_seconds += now - self._start[me]
                    self._busy -= 1
                    if self._busy == 0:
                        self.seconds += now - self._since


@contextmanager
def compile_timer() -> Iterator[CompileTime]:
    """Measure the kernel compilation inside the block.

    Loading a kernel from the cache is not compilation and costs a few
    milliseconds; only real compilations are counted.

    Examples
    --------
    >>> with compile_timer() as timer:
    ...     pass
    >>> timer.seconds, timer.functions
    (0.0, 0)
    """
    from numba.core import event

    timer = CompileTime()

    class _Listener(event.Listener):
        def on_start(self, ev: Any) -> None:
            timer._event(ev)

        def on_end(self, ev: Any) -> None:
            timer._event(ev)

    with event.install_listener("numba:compile", _Listener()):
        yield timer


def compile_kernels(report: Callable[[str, float], None] | None = None) -> CompileTime:
    """Compile (or load from the cache) every built-in kernel by using it once.

    Packs the tiny variants of :data:`VARIANTS` whose plugins are registered,
    runs every registered analyzer of its dimension on each and writes each
    2D one with every registered exporter into a temporary folder, which is
    then removed.

    Parameters
    ----------
    report
        Called as ``report(step, seconds)`` after each step.

    Returns
    -------
    CompileTime
        The compilation time of the whole call (zero when everything was cached).
    """
    from regopack.analysis import dimensions_of
    from regopack.api import analyze, export, pack, scene
    from regopack.errors import RegopackError
    from regopack.manager import default_registry
    from regopack.packing import Packing

    registry = default_registry()
    by_dimension = {
        d: [n for n in sorted(registry.names("analysis")) if d in dimensions_of(registry, n)]
        for d in (2, 3)
    }
    analyzers = by_dimension[2]
    from regopack.exporting import exporter_dimensions

    # the 3D exporters compile nothing (plain numpy); 3D variants are only packed and analysed
    exporters = [
        n for n in sorted(registry.names("export")) if 2 in exporter_dimensions(registry, n)
    ]
    with compile_timer() as total, tempfile.TemporaryDirectory(prefix="regopack-") as folder:
        for k, (label, changes) in enumerate(VARIANTS):
            start = time.perf_counter()
            try:
                resolved = scene("small", registry=registry, **{**TINY, **changes})
            except RegopackError:
                continue  # a plugin of this variant is not installed
            packing = pack(resolved)
            if not isinstance(packing, Packing):  # 3D packings have no exports yet
                analyze(packing, by_dimension[3], registry=registry)
                if report is not None:
                    report(f"{label}: packed, analysed", time.perf_counter() - start)
                continue
            # the analyses and exports of every variant: some kernels have a
            # signature per domain kind (periodic images) or per particle kind
            results = analyze(packing, analyzers, registry=registry)
            for name in exporters:
                target = Path(folder) / f"{k}-{name}"
                target.mkdir()
                export(packing, name, target, analyses=results, registry=registry)
            if report is not None:
                report(f"{label}: packed, analysed, exported", time.perf_counter() - start)
    return total

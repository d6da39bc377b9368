"""Compile the kernels of the suite's stages in a second process while it runs.

``conftest.py`` starts this script when a large test session meets a cold
kernel cache (a fresh clone, as in CI). The test process compiles what its
first tests need (the paper's loop for sharp polygons on several threads, the
contacts) while this one compiles, stage by stage (:data:`STAGE_STEPS`, in
the order of ``KERNEL_STAGES`` in ``conftest.py``), the paper's loop for
sharp polygons on one thread (what worker processes run) with the other 2D
analyses and the exports, the paper's loop for disks, the 3D scans
(polyhedra on two threads and on one, spheres) and analyses, then the loops
of exact refusals and RSA and the sweep (sharp polygons or rounded
particles, on one thread or several).
Both processes write the same on-disk cache (:mod:`regopack.base.jit`).

With a fourth and fifth argument, ``part`` and ``parts``, it compiles only its
share of each stage (:func:`steps_of`): a session of two workers starts two.
After each stage the script writes the stage's number into the file named by
its third argument; the first test of a stage waits for that number while
this process runs (``conftest.py``), rather than compiling the same kernels
at the same time. Between steps the script stops once the process named by
its first argument (the test session) has gone; at the end it creates the
file named by its second argument, which tells later sessions that the cache
is warm (of several processes, the session creates it once all have ended
well).

The imports are made here, not in :func:`main`: the suite imports this module
(``tests/test_kernel_warmup.py``), so that a name that moves fails a test
rather than the warm-up, whose output only a log file keeps.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path
from typing import Any

import numba

import regopack
from regopack.api.warmup import TINY, VARIANTS
from regopack.exports.pipeline import exporter_dimensions
from regopack.registry.manager import default_registry
from regopack.scenes.analysis_plan import dimensions_of

DISKS: dict[str, Any] = {"phases.0.shape": {"kind": "disk"}}
SWEEP: dict[str, Any] = {"insertion.order": "sweep"}
BOX: dict[str, Any] = dict(VARIANTS)["polyhedra in a box (3D)"]
"""A tiny 3D packing (given every 3D analysis)."""
SPHERES: dict[str, Any] = dict(VARIANTS)["spheres in a box (3D)"]

Step = tuple[dict[str, Any], int, bool]
"""Changes to the tiny ``small`` scene, numba's threads, and whether the packing is
also analysed (every analysis of its dimension) and, in 2D, written by every exporter."""

STAGE_STEPS: tuple[tuple[Step, ...], ...] = (
    # before the stages: the paper's loop for sharp polygons on one thread, the analyses
    # and the exports (the test process compiles the loop on several threads itself)
    (({}, 1, True),),
    # 1: the paper's loop for disks
    ((DISKS, 2, False), (DISKS, 1, True)),
    # 2: three dimensions: polyhedra with the partner thread and without, spheres
    ((BOX, 2, False), (BOX, 1, True), (SPHERES, 1, False)),
    # 3: exact refusals, RSA and the sweep (sharp or rounded, on threads or one)
    (
        ({"insertion.screening": "exact"}, 1, False),
        ({"insertion": {"kind": "rsa"}}, 1, False),
        (SWEEP, 2, False),
        (SWEEP, 1, False),
        ({**SWEEP, **DISKS}, 2, False),
        ({**SWEEP, **DISKS}, 1, False),
    ),
    # 4: the modules that run every kind of scene need nothing more
    (),
)
"""The steps of each stage: index ``n`` holds what the modules of stage ``n`` of
``KERNEL_STAGES`` (``conftest.py``) compile first; index 0 what the unlisted modules
compile after their first tests."""

SECOND_PART = frozenset({(2, 0), (2, 1), (2, 2), (3, 0), (3, 1), (3, 2), (3, 3)})
"""The ``(stage, step)`` pairs that the second of two warm-up processes compiles (the 3D
scans, the exact refusals, RSA and the sweep of sharp polygons); the first compiles the
rest (about three minutes each on an idle machine, against six for one process)."""


def steps_of(part: int, parts: int) -> list[list[Step]]:
    """Return, per stage, the steps that process ``part`` of ``parts`` compiles."""
    if parts <= 1:
        return [list(steps) for steps in STAGE_STEPS]
    if part > 1:  # the steps are shared between two processes: a third has none
        return [[] for _ in STAGE_STEPS]
    return [
        [step for m, step in enumerate(steps) if ((n, m) in SECOND_PART) == (part == 1)]
        for n, steps in enumerate(STAGE_STEPS)
    ]


def _finish(packing: Any) -> None:
    """Give ``packing`` every analysis of its dimension and, in 2D, write it with every
    exporter (some kernels have a signature per particle kind)."""
    registry = default_registry()
    dim = packing.dimension
    names = [n for n in sorted(registry.names("analysis")) if dim in dimensions_of(registry, n)]
    results = regopack.analyze(packing, names, registry=registry)
    if dim == 3:
        return
    exporters = sorted(registry.names("export"))
    exporters = [n for n in exporters if 2 in exporter_dimensions(registry, n)]
    with tempfile.TemporaryDirectory(prefix="regopack-warmup-") as folder:
        for name in exporters:
            target = Path(folder) / name
            target.mkdir()
            regopack.export(packing, name, target, analyses=results, registry=registry)


def _record(progress: Path | None, stage: int) -> None:
    """Write ``stage`` into ``progress`` at once (a reader never sees half a number)."""
    if progress is None:
        return
    part = progress.with_name(progress.name + ".part")
    part.write_text(str(stage))
    part.replace(progress)


def main() -> None:
    """Pack each step's tiny scene once (compiling or loading its kernels)."""
    parent = int(sys.argv[1]) if len(sys.argv) > 1 else os.getppid()
    progress = Path(sys.argv[3]) if len(sys.argv) > 3 else None
    part = int(sys.argv[4]) if len(sys.argv) > 4 else 0
    parts = int(sys.argv[5]) if len(sys.argv) > 5 else 1
    most = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
    for stage, steps in enumerate(steps_of(part, parts)):
        for changes, threads, finish in steps:
            if os.getppid() != parent:
                return
            numba.set_num_threads(min(threads, most))
            packing = regopack.pack("small", **{**TINY, **changes})
            if finish:
                _finish(packing)
        _record(progress, stage)
    if len(sys.argv) > 2 and parts <= 1:  # of several, the session marks the cache warm
        Path(sys.argv[2]).touch()


if __name__ == "__main__":
    main()

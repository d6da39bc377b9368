"""Compile the kernels of the suite's later stages in a second process while it runs.

``conftest.py`` starts this script when a large test session meets a cold
kernel cache (a fresh clone, as in CI). The test process compiles what its
first tests need (the paper's loop for sharp polygons, the analyses) while this
one compiles, in the order of the suite's later stages (``KERNEL_STAGES`` in
``conftest.py``), the paper's loop for disks, the four variants of the sweep
(sharp polygons or rounded particles, on one thread or several), the loops of
exact refusals and RSA, then the 3D scan and analyses. Both processes write the
same on-disk cache (:mod:`regopack.base.jit`); a test that reaches a kernel first
compiles it itself, with the same result. Between steps the script stops once the process named by
its first argument (the test session) has gone; at the end it creates the file
named by its second argument, which tells later sessions that the cache is warm.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import Any

import numba

import regopack
from regopack.api.warmup import TINY, VARIANTS

DISKS: dict[str, Any] = {"phases.0.shape": {"kind": "disk"}}

STEPS: tuple[tuple[dict[str, Any], int], ...] = (
    (DISKS, 2),
    (DISKS, 1),
    ({"insertion.order": "sweep", **DISKS}, 2),
    ({"insertion.order": "sweep", **DISKS}, 1),
    ({"insertion.order": "sweep"}, 2),
    ({"insertion.order": "sweep"}, 1),
    ({"insertion.screening": "exact"}, 1),
    ({"insertion": {"kind": "rsa"}}, 1),
)
"""Scene changes and thread counts, in the order of the suite's stages
(``KERNEL_STAGES`` in ``conftest.py``): the paper's loop for disks, the sweep,
exact refusals and RSA."""

BOX: dict[str, Any] = next(c for label, c in VARIANTS if label.endswith("(3D)"))
"""The last step: a tiny 3D packing, packed and given every 3D analysis (the last
stage of the suite)."""


def main() -> None:
    """Pack each step's tiny scene once (compiling or loading its kernels)."""
    from regopack.analysis.pipeline import dimensions_of
    from regopack.registry.manager import default_registry

    parent = int(sys.argv[1]) if len(sys.argv) > 1 else os.getppid()
    most = numba.config.NUMBA_NUM_THREADS  # type: ignore[attr-defined]
    for changes, threads in STEPS:
        if os.getppid() != parent:
            return
        numba.set_num_threads(min(threads, most))
        regopack.pack("small", **{**TINY, **changes})
    if os.getppid() != parent:
        return
    registry = default_registry()
    names = [n for n in sorted(registry.names("analysis")) if 3 in dimensions_of(registry, n)]
    regopack.analyze(regopack.pack("small", **{**TINY, **BOX}), names)
    if len(sys.argv) > 2:
        Path(sys.argv[2]).touch()


if __name__ == "__main__":
    main()

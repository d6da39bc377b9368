"""Scenes, kernel warm-ups and the packings shared by the benchmarks.

Every benchmark packs through the public API. The compiled kernels are
cached on disk by numba; :func:`warm_kernels` (a ``setup_cache``, run once per
commit before the benchmarks that use it) compiles them on a cold cache, and
each benchmark's ``setup`` packs a tiny scene of its own kind first, so that
loading the kernels is never timed.

The sizes are module-level values so that ``tests/test_benchmarks_suite.py``
can run every benchmark on tiny scenes.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import regopack

MODES_2D = ("reference", "dem")
"""``reference``: the built-in scene ``table1`` (the paper's order);
``dem``: the built-in scene ``dem`` (the homogeneous sweep, paced closing)."""

SHAPES_3D = ("polyhedra", "spheres")
"""``polyhedra``: the built-in scene ``table1-3d``; ``spheres``: the same
population with every phase a sphere."""

SIZE_3D = {"size.d_max": 12.0}
"""The 3D benchmarks cut the Chang'e-5 sizes to 2-12 µm, so that boxes of a
few tens of µm hold thousands of particles (``table1-3d`` itself, sizes
2-40 µm in a 150 µm cube, takes about five minutes to pack)."""

QUICK = {"rounds": 1, "repeat": (1, 5, 5.0), "warmup_time": 0.0}
"""asv's timing settings for the benchmarks that take under a few seconds a
call (analyses, exports, verification): one process per parameter, up to
five samples or five seconds in it, no extra warm-up call (``setup`` loads
the kernels once per process). Each process costs seconds of its own
(imports, loading the packing and the kernels), so one round keeps the suite
short; the packing benchmarks keep asv's two rounds."""

SCENE_SIDE = 800.0
"""Side (µm) of the 2D scenes ``table1`` and ``dem``, and of the benchmarks of settings."""

WARM_SIDE_2D = 60.0
"""Side (µm) of the tiny 2D scenes that load the kernels before a timing."""

WARM_SIDE_PERIODIC = 150.0
"""Side (µm) of the tiny periodic squares: wider than four of the largest particles."""

WARM_SIDE_3D = 20.0
"""Side (µm) of the tiny 3D boxes that load the kernels before a timing."""

THREADS_SIDES_3D: dict[str, float] = {"sweep": 60.0, "paper": 40.0}
"""Side (µm) of the cubes of ``packing.Threads3D``: the sweep's and the paper's order's."""

SHARED_SIDES: dict[str, float] = {
    "reference": 800.0,  # table1 itself: 16 579 drawn, 15 261 placed
    "dem": 800.0,  # dem itself: 16 579 drawn, about 14 700 placed
    "polyhedra": 60.0,  # about 2 000 drawn, 1 700 placed
    "spheres": 60.0,
}
"""Side (µm) of the packings that the analysis, export and verification
benchmarks share (packed once per commit by :func:`shared_packings`)."""


def disks() -> dict[str, Any]:
    """Overrides that make every phase of a Table-1 scene an exact disk."""
    return {f"phases.{i}.shape": {"kind": "disk"} for i in range(6)}


def spheres() -> dict[str, Any]:
    """Overrides that make every phase of ``table1-3d`` a sphere."""
    return {f"phases.{i}.shape": {"kind": "sphere"} for i in range(6)}


def scene_2d(mode: str, side: float, **overrides: Any) -> Any:
    """A square ``side`` µm wide of the built-in scene of a 2D ``mode``."""
    name = {"reference": "table1", "dem": "dem"}[mode]
    return regopack.scene(name, **{"domain.width": side, "domain.height": side, **overrides})


def scene_3d(shape: str, side: float, base: str = "table1-3d", **overrides: Any) -> Any:
    """A cube ``side`` µm wide of a 3D scene (sizes 2-12 µm) with ``shape`` particles."""
    extra = spheres() if shape == "spheres" else {}
    box = {"domain.width": side, "domain.height": side, "domain.depth": side}
    return regopack.scene(base, **{**box, **SIZE_3D, **extra, **overrides})


_WARM: dict[Any, Any] = {}
"""What this process has warmed up already, with its result: asv runs a
benchmark's ``setup`` again before every sample, and a warm-up is needed once
per process (each benchmark runs in a process of its own)."""


def once(key: Any, make: Any) -> Any:
    """``make()`` the first time ``key`` is asked for in this process, its result after."""
    if key not in _WARM:
        _WARM[key] = make()
    return _WARM[key]


def tiny_2d(mode: str, **overrides: Any) -> Any:
    """A tiny square of a 2D mode, packed once per process (this loads its kernels)."""
    key = ("2d", mode, WARM_SIDE_2D, repr(sorted(overrides.items())))
    return once(key, lambda: regopack.pack(scene_2d(mode, WARM_SIDE_2D, **overrides), verify=False))


def tiny_3d(shape: str) -> Any:
    """A tiny box of a 3D shape, packed once per process (this loads its kernels)."""
    key = ("3d", shape, WARM_SIDE_3D)
    return once(key, lambda: regopack.pack(scene_3d(shape, WARM_SIDE_3D), verify=False))


def warm_2d(mode: str, **overrides: Any) -> None:
    """Load (or compile) the kernels of a 2D mode: pack a tiny square of it."""
    tiny_2d(mode, **overrides)


def warm_3d(shape: str) -> None:
    """Load (or compile) the kernels of a 3D shape: pack a tiny box of it."""
    tiny_3d(shape)


def warm_kernels() -> str:
    """Compile every kernel the packing benchmarks use (a no-op on a warm cache).

    A ``setup_cache``: asv runs it once per commit, in its own process and
    with its own timeout, before the first benchmark that names it, so that a
    cold cache (a new commit) is compiled outside every benchmark's timeout.
    Returns a word, not ``None``: asv passes the cache to the benchmarks only
    when it is not ``None``, and their signatures take it.
    """
    for mode in MODES_2D:
        warm_2d(mode)
        warm_2d(mode, **disks())
    periodic = {"kind": "periodic", "width": WARM_SIDE_PERIODIC, "height": WARM_SIDE_PERIODIC}
    regopack.pack(regopack.scene("table1", domain=periodic), verify=False)
    for shape in SHAPES_3D:
        warm_3d(shape)
    return "warm"


warm_kernels.timeout = 1800  # type: ignore[attr-defined]  # compiling on a cold cache


def shared_packings() -> dict[str, Any]:
    """Pack the 2D and 3D packings of :data:`SHARED_SIDES` once, into the cache folder.

    A ``setup_cache`` shared by the analysis, export and verification
    benchmarks (asv keys it by this function, so it runs once per commit).
    Returns the path of each packing file and its run summary.
    """
    out: dict[str, Any] = {}
    folder = Path(os.getcwd())
    for key, side in SHARED_SIDES.items():
        if key in MODES_2D:
            scene = scene_2d(key, side)
        else:
            scene = scene_3d(key, side)
        outcome = regopack.pack_and_summarise(scene, verify=False)
        path = folder / f"{key}.npz"
        regopack.save(outcome.packing, path)
        out[key] = {"path": str(path), "summary": dict(outcome.summary)}
    return out


shared_packings.timeout = 1800  # type: ignore[attr-defined]

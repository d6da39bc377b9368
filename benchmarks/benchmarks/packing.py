"""Packing: time and peak memory of each mode and dimension against the domain's size.

``time_pack`` is the wall time of ``regopack.pack`` (drawing the particles,
the insertion and the run's summary; no verification, no files), measured
after the kernels are loaded. ``peakmem_pack`` is the peak resident memory of
the process that packs (Python, numpy, numba and the kernels included).
"""

from __future__ import annotations

import math
from typing import Any

import numba

import regopack

from . import common

SLOW = {
    "number": 1,  # one packing per sample
    "warmup_time": 0.0,  # the setup's tiny packing is the warm-up
    "min_run_count": 1,
    "repeat": (1, 3, 10.0),  # 1 to 3 samples a round, fewer past 10 s
    "timeout": 600.0,
}
"""asv's timing attributes for benchmarks that take seconds a call."""


class _Slow:
    number = SLOW["number"]
    warmup_time = SLOW["warmup_time"]
    min_run_count = SLOW["min_run_count"]
    repeat = SLOW["repeat"]
    timeout = SLOW["timeout"]
    setup_cache = staticmethod(common.warm_kernels)


class Pack2D(_Slow):
    """2D: the paper's order (``table1``) and the homogeneous sweep (``dem``) in squares.

    Sides 200-1600 µm: about 1 000, 4 100, 16 600 and 66 300 particles drawn
    (800 µm is the scenes' own size).
    """

    params = (list(common.MODES_2D), [200.0, 400.0, 800.0, 1600.0])
    param_names = ["mode", "side_um"]

    def setup(self, _cache: Any, mode: str, side: float) -> None:
        common.warm_2d(mode)
        self.scene = common.scene_2d(mode, side)

    def time_pack(self, _cache: Any, mode: str, side: float) -> None:
        regopack.pack(self.scene, verify=False)

    def peakmem_pack(self, _cache: Any, mode: str, side: float) -> None:
        regopack.pack(self.scene, verify=False)


class Pack3D(_Slow):
    """3D: ``table1-3d`` polyhedra and the same population as spheres, in cubes.

    Sizes 2-12 µm (see :data:`common.SIZE_3D`), the paper's order.
    """

    params = (list(common.SHAPES_3D), [30.0, 45.0, 60.0])
    param_names = ["shape", "side_um"]

    def setup(self, _cache: Any, shape: str, side: float) -> None:
        common.warm_3d(shape)
        self.scene = common.scene_3d(shape, side)

    def time_pack(self, _cache: Any, shape: str, side: float) -> None:
        regopack.pack(self.scene, verify=False)

    def peakmem_pack(self, _cache: Any, shape: str, side: float) -> None:
        regopack.pack(self.scene, verify=False)


class Sweep3D(_Slow):
    """3D: the homogeneous sweep of ``dem3d`` (sizes 2-12 µm) in boxes twice as tall as wide.

    Polyhedra and spheres, the paced closing (the scene's) and the tail
    closing, one column over the floor.
    """

    params = (list(common.SHAPES_3D), ["paced", "tail"], [30.0, 45.0])
    param_names = ["shape", "closing", "side_um"]

    def setup(self, _cache: Any, shape: str, closing: str, side: float) -> None:
        common.warm_3d(shape)
        self.scene = common.scene_3d(
            shape,
            side,
            base="dem3d",
            **{"domain.height": 2.0 * side, "insertion.closing": closing, "insertion.strip": 0.0},
        )

    def time_pack(self, _cache: Any, shape: str, closing: str, side: float) -> None:
        regopack.pack(self.scene, verify=False)

    def peakmem_pack(self, _cache: Any, shape: str, closing: str, side: float) -> None:
        regopack.pack(self.scene, verify=False)


class SweepScale3D(_Slow):
    """3D: the sweep of spheres (sizes 2-12 µm) in cubes of about 10^3, 10^4 and 10^5 spheres.

    Columns 45 µm wide and the tail closing; the time per sphere should not
    grow with the cube (the candidate search descends per-column trees).
    """

    params = ([55.0, 120.0, 256.0],)
    param_names = ["side_um"]

    def setup(self, _cache: Any, side: float) -> None:
        common.warm_3d("spheres")
        self.scene = common.scene_3d(
            "spheres",
            side,
            base="dem3d",
            **{"insertion.closing": "tail", "insertion.strip": 45.0, "outputs.fabric": False},
        )

    def time_pack(self, _cache: Any, side: float) -> None:
        regopack.pack(self.scene, verify=False)

    def peakmem_pack(self, _cache: Any, side: float) -> None:
        regopack.pack(self.scene, verify=False)


class Threads(_Slow):
    """One kernel thread against two: the partner thread and the sweep's parallel scans.

    The scenes at their own size (800 µm). Two threads need two cores; where
    fewer exist both rows run on what there is.
    """

    params = (list(common.MODES_2D), [1, 2])
    param_names = ["mode", "threads"]

    def setup(self, _cache: Any, mode: str, threads: int) -> None:
        self.before = numba.get_num_threads()
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
        common.warm_2d(mode)
        self.scene = common.scene_2d(mode, common.SCENE_SIDE)

    def teardown(self, _cache: Any, mode: str, threads: int) -> None:
        numba.set_num_threads(self.before)

    def time_pack(self, _cache: Any, mode: str, threads: int) -> None:
        regopack.pack(self.scene, verify=False)


class Threads3D(_Slow):
    """3D: one kernel thread against two (the partner thread of the polyhedron scans).

    ``dem3d``'s polyhedra (sizes 2-12 µm) in a 60 µm cube, the sweep with the
    tail closing and columns of 45 µm, and the paper's order in a 40 µm cube.
    """

    params = (["sweep", "paper"], [1, 2])
    param_names = ["order", "threads"]

    def setup(self, _cache: Any, order: str, threads: int) -> None:
        self.before = numba.get_num_threads()
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
        common.warm_3d("polyhedra")
        if order == "sweep":
            over = {"insertion.closing": "tail", "insertion.strip": 45.0}
            side = common.THREADS_SIDES_3D["sweep"]
            self.scene = common.scene_3d("polyhedra", side, base="dem3d", **over)
        else:
            self.scene = common.scene_3d("polyhedra", common.THREADS_SIDES_3D["paper"])

    def teardown(self, _cache: Any, order: str, threads: int) -> None:
        numba.set_num_threads(self.before)

    def time_pack(self, _cache: Any, order: str, threads: int) -> None:
        regopack.pack(self.scene, verify=False)


class NeighbourLists(_Slow):
    """``insertion.neighbour_lists`` on and off: the paper's order, 800 µm (same packing)."""

    params = [True, False]
    param_names = ["neighbour_lists"]

    def setup(self, _cache: Any, lists: bool) -> None:
        common.warm_2d("reference")
        self.scene = common.scene_2d(
            "reference", common.SCENE_SIDE, **{"insertion.neighbour_lists": lists}
        )

    def time_pack(self, _cache: Any, lists: bool) -> None:
        regopack.pack(self.scene, verify=False)

    def peakmem_pack(self, _cache: Any, lists: bool) -> None:
        regopack.pack(self.scene, verify=False)


def domain(kind: str, area: float) -> dict[str, Any]:
    """A domain of ``kind`` with the given area (the hexagon is regular)."""
    side = math.sqrt(area)
    if kind in ("rectangle", "periodic"):
        return {"kind": kind, "width": side, "height": side}
    if kind == "circle":
        return {"kind": "circle", "radius": side / math.sqrt(math.pi)}
    r = side * math.sqrt(2.0 / (3.0 * math.sqrt(3.0)))  # circumradius of the hexagon
    corners = [[r * math.cos(k * math.pi / 3), r * math.sin(k * math.pi / 3)] for k in range(6)]
    return {"kind": "polygon", "vertices": corners}


class Domains(_Slow):
    """The paper's order in every domain kind, octagons and disks, the area of 400 × 400 µm².

    Every run draws the same 4 145 particles.
    """

    params = (["rectangle", "periodic", "circle", "polygon"], ["octagons", "disks"])
    param_names = ["domain", "shapes"]

    def setup(self, _cache: Any, kind: str, shapes: str) -> None:
        extra = common.disks() if shapes == "disks" else {}
        side = common.WARM_SIDE_PERIODIC if kind == "periodic" else common.WARM_SIDE_2D
        warm = regopack.scene("table1", domain=domain(kind, side**2), **extra)
        common.once(("domain", kind, shapes), lambda: regopack.pack(warm, verify=False))
        area = (common.SCENE_SIDE / 2) ** 2
        self.scene = regopack.scene("table1", domain=domain(kind, area), **extra)

    def time_pack(self, _cache: Any, kind: str, shapes: str) -> None:
        regopack.pack(self.scene, verify=False)


class Cylinder3D(_Slow):
    """3D: the sweep of ``dem3d`` (sizes 2-12 µm) in a cylinder, against a box of its volume.

    The side wall is the prism inscribed in it whose facets lie at most
    ``insertion.wall_gap`` smallest diameters inside; ``box`` packs a square
    box of the same volume and height. The cylinder's radius is half the side.
    """

    params = (list(common.SHAPES_3D), ["box", "0.01", "0.001", "1e-05"], [60.0])
    param_names = ["shape", "wall_gap", "side_um"]

    def setup(self, _cache: Any, shape: str, gap: str, side: float) -> None:
        common.warm_3d(shape)
        radius, height = side / 2.0, side
        if gap == "box":
            width = math.sqrt(math.pi) * radius
            domain = {"kind": "box", "width": width, "depth": width, "height": height}
            extra: dict[str, float] = {}
        else:
            domain = {"kind": "cylinder", "radius": radius, "height": height}
            extra = {"insertion.wall_gap": float(gap)}
        shapes = common.spheres() if shape == "spheres" else {}
        domain["center"] = [0.0, 0.0, 0.0]
        self.scene = regopack.scene(
            "dem3d", domain=domain, **{**common.SIZE_3D, **shapes, "outputs.fabric": False, **extra}
        )

    def time_pack(self, _cache: Any, shape: str, gap: str, side: float) -> None:
        regopack.pack(self.scene, verify=False)

"""Verification (``regopack.verify``): the independent overlap check of the shared packings.

2D: shapely polygons (``table1`` and ``dem`` at 800 µm); 3D: the polyhedra
and spheres of the 60 µm cubes.
"""

from __future__ import annotations

from typing import Any

import regopack

from . import common


class Verify:
    """``regopack.verify`` on each shared packing; a packing that fails is an error."""

    setup_cache = staticmethod(common.shared_packings)
    timeout = 600.0
    rounds = common.QUICK["rounds"]
    repeat = common.QUICK["repeat"]
    warmup_time = common.QUICK["warmup_time"]
    params = [list(common.SHARED_SIDES)]
    param_names = ["packing"]

    def setup(self, cache: dict[str, Any], key: str) -> None:
        path = cache[key]["path"]
        self.packing = common.once(("load", path), lambda: regopack.load(path))
        if key in common.SHAPES_3D:  # load the 3D check's kernels
            common.once(("verify", key), lambda: regopack.verify(common.tiny_3d(key)))

    def time_verify(self, cache: dict[str, Any], key: str) -> None:
        report = regopack.verify(self.packing)
        if not report:
            raise AssertionError(f"{key}: the packing does not verify: {report}")

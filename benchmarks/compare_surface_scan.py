"""Time the 3D scan kernel of two builds in one process, alternating run by run.

The other build is a copy of ``plugins/inserters/available_surface`` exported
as a top-level package (its imports renamed), for example the one of branch
``dupins``::

    mkdir -p /tmp/ab/before
    git archive dupins plugins/inserters/available_surface \\
        | tar -x -C /tmp/ab/before --strip-components=3
    sed -i 's/regopack\\.plugins\\.inserters\\.available_surface/before/g' /tmp/ab/before/*.py

Each run packs the scene with the inserter's state calling either build's
``scan`` (everything else is this checkout's); rounds alternate the order,
every pair is checked to place the same centres bit for bit, and the
insertion times and their ratios are printed. The build loaded and warmed
first runs a few per cent faster whichever it is
(docs/development/2026-12-04-comparing-builds.md): run once with each
``--first`` and take both. Run from the repository root:

    python benchmarks/compare_surface_scan.py --other /tmp/ab --first other \\
        --set domain.width=60 --set domain.depth=60 --set domain.height=100 \\
        --set size.d_max=12 --set insertion.order=sweep \\
        --set 'insertion.closing="tail"' --set insertion.strip=45
"""

from __future__ import annotations

import argparse
import importlib
import math
import platform
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

import regopack.plugins.inserters.available_surface.state as state_module
from regopack.plugins.inserters.available_surface.analysis import scan as this_scan
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene

WARM = ["domain.width=20", "domain.depth=20", "domain.height=20", "size.d_max=12", "count=30"]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--other", required=True, help="folder holding the other build's package")
    parser.add_argument("--package", default="before", help="the other build's package name")
    parser.add_argument("--scene", default="table1-3d")
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--first", choices=["this", "other"], default="other")
    args = parser.parse_args()
    if args.rounds < 1:
        parser.error("--rounds must be 1 or more")
    sys.path.insert(0, args.other)
    try:
        other_scan = importlib.import_module(f"{args.package}.analysis").scan
    except ImportError as err:
        parser.error(f"--other {args.other}: no build {args.package!r} there ({err})")
    scans: dict[str, Callable[..., Any]] = {"this": this_scan, "other": other_scan}
    registry = default_registry()
    # a warm-up in the scene's shape kind (the phases' overrides apply to it too)
    warm = WARM + [o for o in args.overrides if o.startswith("phases.")]

    def run(which: str, overrides: list[str]) -> tuple[float, Any]:
        state_module.scan = scans[which]  # type: ignore[attr-defined]
        result = run_scene(resolve_scene(load_scene(args.scene, overrides), registry), None)
        return float(result.summary["insert_time_s"]), result

    order = [args.first, "this" if args.first == "other" else "other"]
    for which in order:
        started = time.perf_counter()
        run(which, warm)
        print(f"warm-up {which}: {time.perf_counter() - started:.1f} s", flush=True)
    times: dict[str, list[float]] = {"this": [], "other": []}
    for r in range(args.rounds):
        centres = {}
        for which in order if r % 2 == 0 else order[::-1]:
            t, result = run(which, args.overrides)
            times[which].append(t)
            centres[which] = np.asarray(result.packing.centre)
            placed = result.summary["placed"]
            print(f"round {r} {which}: {t:.2f} s, {placed} placed", flush=True)
        same = np.array_equal(centres["this"], centres["other"], equal_nan=True)
        print(f"  the same centres: {same}", flush=True)
    ratios = [o / t for o, t in zip(times["other"], times["this"], strict=True)]
    print(f"machine: {platform.machine()}, Python {platform.python_version()}")
    for which, values in times.items():
        print(f"{which}: " + ", ".join(f"{v:.2f}" for v in values) + " s")
    geo = math.exp(sum(math.log(x) for x in ratios) / len(ratios))
    each = ", ".join(f"{x:.3f}" for x in ratios)
    print(f"other / this per round: {each} (geometric mean {geo:.3f})")


if __name__ == "__main__":
    main()

"""Cylinders: what the side wall's prism costs and leaves, against a box of the same volume.

Packs `dem3d`'s population (sizes cut to 2-12 µm; polyhedra, or spheres
with ``--spheres``) in a cylinder, once per ``insertion.wall_gap``, and once
in a box of the same volume and height, each in the same process after a
tiny packing that loads the kernels; prints per run the prism's facets, the
particles placed, the insertion time, the analyses, the gap between the
wall and the particle nearest it (in smallest diameters) and φ over the
domain. Run from the repository root:

    python benchmarks/bench_cylinder.py --radius 30 --height 60
    python benchmarks/bench_cylinder.py --radius 30 --height 60 --spheres
"""

from __future__ import annotations

import argparse
import math
import time
import tomllib
from importlib import resources
from typing import Any

import numpy as np

import regopack
from regopack.plugins.inserters.available_surface.prism_wall import facet_count


def scene(domain: dict[str, Any], spheres: bool, order: str, gap: float) -> dict[str, Any]:
    """`dem3d` with sizes 2-12 µm in ``domain``, packed in ``order``."""
    text = resources.files("regopack.scenes").joinpath("dem3d.toml").read_text()
    data = tomllib.loads(text)
    data["domain"] = domain
    data["size"]["d_max"] = 12.0
    if spheres:
        for phase in data["phases"]:
            phase["shape"] = {"kind": "sphere"}
    insertion = {"kind": "available-surface", "order": order}
    if domain["kind"] == "cylinder":
        insertion["wall_gap"] = gap
    data["insertion"] = insertion
    data["outputs"] = {"fabric": False}
    return data


def outermost_gap(packing: regopack.Packing) -> float:
    """Smallest distance from the side wall to a particle, in smallest equivalent diameters."""
    d = packing.domain
    order = packing.placed_in_order()
    if packing.rounded:
        c = packing.centre[order]
        reach = np.hypot(c[:, 0] - d.cx, c[:, 1] - d.cy) + packing.solids.circumradius[order]
    else:
        reach = np.array(
            [
                np.hypot(v[:, 0] - d.cx, v[:, 1] - d.cy).max()
                for v in (packing.world_vertices(int(k)) for k in order)
            ]
        )
    return float((d.radius - reach.max()) / (2.0 * packing.radius.min()))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--radius", type=float, default=30.0, help="cylinder radius (µm)")
    parser.add_argument("--height", type=float, default=60.0, help="cylinder height (µm)")
    parser.add_argument("--spheres", action="store_true", help="spheres instead of polyhedra")
    parser.add_argument("--order", choices=["paper", "sweep"], default="sweep")
    parser.add_argument(
        "--gaps", type=float, nargs="+", default=[0.1, 0.01, 1e-3, 1e-5], help="wall gaps"
    )
    args = parser.parse_args()
    if not (args.radius > 0 and args.height > 0 and all(g > 0 for g in args.gaps)):
        parser.error("radius, height and gaps must be positive")
    tiny = {"kind": "cylinder", "radius": 8.0, "height": 16.0, "center": [0.0, 0.0, 0.0]}
    regopack.pack(scene(tiny, args.spheres, args.order, 1e-3), verify=False)
    cyl = {"kind": "cylinder", "radius": args.radius, "height": args.height}
    side = math.sqrt(math.pi) * args.radius
    box = {"kind": "box", "width": side, "depth": side, "height": args.height}
    shape = "spheres" if args.spheres else "polyhedra"
    print(f"{shape}, order {args.order}, cylinder R = {args.radius:g} µm, H = {args.height:g} µm")
    runs: list[tuple[str, dict[str, Any], float]] = [("box", box, 0.0)]
    runs += [(f"gap {g:g}", cyl, g) for g in args.gaps]
    for label, domain, gap in runs:
        data = scene({**domain, "center": [0.0, 0.0, 0.0]}, args.spheres, args.order, gap)
        started = time.perf_counter()
        packing = regopack.pack(data, verify=False)
        wall = time.perf_counter() - started
        stats = packing.stats
        d_min = 2.0 * float(packing.radius.min())
        facets = facet_count(args.radius, gap * d_min) if gap else 0
        near = outermost_gap(packing) if gap else math.nan
        print(
            f"{label:>10}: facets {facets:6d}, placed {packing.n_placed:6d}, "
            f"insertion {stats['insert_time_s']:6.2f} s ({wall:6.2f} s in all), "
            f"analyses {int(stats['candidate_analyses']):7d}, nearest to the wall "
            f"{near:.2e} d_min, phi {packing.phi:.4f}",
            flush=True,
        )


if __name__ == "__main__":
    main()

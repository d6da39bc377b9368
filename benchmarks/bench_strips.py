"""What the sweep's strips trade: speed against density, and the seams between strips.

Packs the `dem` scene (tail closing) in an L x L domain with each strip width
in turn, in one process, and prints the particles placed, phi over the
interior window and over a bulk band (the middle half of the height, away
from the bottom and the loose top), the insertion time, the candidate
analyses per placed particle, and the number density across each strip
(eight bins from one seam to the next, inner strips only, relative to their
mean). Run from the repository root:

    python benchmarks/bench_strips.py --size 1600 --strips 0 800 400 200 100
"""

from __future__ import annotations

import argparse
import platform

import numpy as np
import shapely

from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=float, default=1600.0)
    parser.add_argument("--strips", type=float, nargs="+", default=[0, 800, 400, 200, 100])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--set", action="append", default=[], dest="overrides")
    args = parser.parse_args()
    registry = default_registry()
    warm = ["domain.width=60", "domain.height=60", "insertion.strip=20"]
    run_scene(resolve_scene(load_scene("dem", warm), registry), None)  # compile
    size = args.size
    half = 0.5 * size
    print(f"machine: {platform.machine()}, Python {platform.python_version()}")
    print(f"dem, L = {size:g}, seed {args.seed}, closing tail, {' '.join(args.overrides)}")
    print(
        f"{'strip':>6} {'n':>3} {'placed':>7} {'phi_int':>8} {'phi_bulk':>8} "
        f"{'time_s':>7} {'an/placed':>9}  number density across a strip (seam to seam, rel.)"
    )
    for strip in args.strips:
        overrides = [
            f"domain.width={size}",
            f"domain.height={size}",
            'insertion.closing="tail"',
            f"insertion.strip={strip}",
            f"seed={args.seed}",
            *args.overrides,
        ]
        outcome = run_scene(resolve_scene(load_scene("dem", overrides), registry), None)
        s = outcome.summary
        p = outcome.packing
        bulk = shapely.box(-half + 40.0, -0.25 * size, half - 40.0, 0.25 * size)
        phi_bulk = shapely.area(shapely.intersection(p.to_shapely(), bulk)).sum() / bulk.area
        nstrip = int(s["strips"])
        profile = ""
        if nstrip >= 3:
            width = size / nstrip
            c = p.centre[p.placed]
            keep = (np.abs(c[:, 0]) < half - width) & (np.abs(c[:, 1]) < 0.25 * size)
            phase = np.mod(c[keep, 0] + half, width) / width
            counts = np.bincount(np.minimum((phase * 8).astype(int), 7), minlength=8)
            profile = " ".join(f"{v:+.3f}" for v in counts / counts.mean() - 1.0)
        per = s["candidate_analyses"] / s["placed"]
        print(
            f"{strip:>6g} {nstrip:>3} {s['placed']:>7} {s['phi_interior']:>8.4f} "
            f"{phi_bulk:>8.4f} {s['insert_time_s']:>7.2f} {per:>9.1f}  {profile}",
            flush=True,
        )


if __name__ == "__main__":
    main()

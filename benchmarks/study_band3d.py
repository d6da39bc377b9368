"""The 3D sweep's layers over the floor: number density and the finest share by height.

Packs the scene ``table1-3d`` in a tall box with ``insertion.order = "sweep"``
and the tail closing (or ``--closing paced``), and prints, per seed and averaged over the seeds, in
slabs over the floor (centres farther than 20 µm from the side walls): the
particle centres per µm of height, and the share of the finest √2 class
(2–2.8 µm) among them over its share of the drawn particles (1: the drawn
mixture). The tail closing leaves its last zone height under the top loose
and coarse; with lags the fine particles still waiting when the zone reaches
the top fill the old pores below it. Run from the repository root::

    python benchmarks/study_band3d.py --width 110 --height 480 --seeds 1 2 [--lag none]

``--lag none`` offers every particle at its turn (no pilot); the default learns
the lags with the pilot, as a scene does. ``--shape sphere`` packs every phase
as spheres.
"""

from __future__ import annotations

import argparse
import itertools
import math
import time

import numpy as np

from regopack.api.functions import pack_and_summarise
from regopack.scenes.model import load_scene

EDGES = (0.0, 20.0, 60.0, 100.0, 150.0, 200.0, 250.0, 300.0, 360.0, 420.0, 480.0)
"""Slab boundaries over the floor (µm)."""
SIDE_MARGIN = 20.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--width", type=float, default=110.0)
    parser.add_argument("--height", type=float, default=480.0)
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--lag", choices=["pilot", "none"], default="pilot")
    parser.add_argument("--shape", choices=["polyhedron", "sphere"], default="polyhedron")
    parser.add_argument("--closing", choices=["tail", "paced"], default="tail")
    args = parser.parse_args()
    w, h = args.width, args.height
    edges = np.array([e for e in EDGES if e < h] + [h])
    # every phase of the scene as spheres (--shape sphere), or its polyhedra
    phases = load_scene("table1-3d").phases
    shapes = (
        {f"phases.{k}.shape": {"kind": "sphere"} for k in range(len(phases))}
        if args.shape == "sphere"
        else {}
    )
    dens, share = [], []
    for seed in args.seeds:
        started = time.perf_counter()
        out = pack_and_summarise(
            "table1-3d",
            seed=seed,
            verify=False,
            **{
                "domain.width": w,
                "domain.depth": w,
                "domain.height": h,
                "insertion.order": "sweep",
                "insertion.closing": args.closing,
                "insertion.lag": args.lag,
                **shapes,
            },
        )
        p = out.packing
        finest = 2.0 * p.radius < 2.0 * math.sqrt(2.0)
        c = p.centre[p.placed]
        fine = finest[p.placed]
        z = c[:, 2] + 0.5 * h  # the box is centred at the origin; height is the third axis
        inner = np.all(np.abs(c[:, :2]) < 0.5 * w - SIDE_MARGIN, axis=1)
        n_all = np.histogram(z[inner], edges)[0]
        n_fine = np.histogram(z[inner & fine], edges)[0]
        dens.append(n_all / np.diff(edges))
        share.append(n_fine / np.maximum(n_all, 1) / float(np.mean(finest)))
        print(
            f"seed {seed}: {int(p.placed.sum())} placed in {time.perf_counter() - started:.1f} s"
            f" (pilot {out.summary.get('pilot_time_s', 0.0):.1f} s)",
            flush=True,
        )
    slabs = [f"{a:g}-{b:g}" for a, b in itertools.pairwise(edges)]
    print("height over the floor (um):", "  ".join(f"{s:>8}" for s in slabs))
    print("centres per um:            ", "  ".join(f"{v:8.1f}" for v in np.mean(dens, axis=0)))
    print("finest share / drawn:      ", "  ".join(f"{v:8.2f}" for v in np.mean(share, axis=0)))


if __name__ == "__main__":
    main()

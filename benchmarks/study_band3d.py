"""The 3D sweep's layers over the floor: number density by height against the bulk's.

Packs the scene ``table1-3d`` in a tall box with ``insertion.order = "sweep"``
and the tail closing, and prints, per seed and on average, the number of
particle centres per µm of height in slabs over the floor, relative to the
bulk (from 150 µm to 120 µm under the top), for all particles and for the
finest √2 class (2–2.8 µm), centres farther than 20 µm from the side walls.
The scene draws ``--count`` particles (20 000: more than fill the default
box, so that the front reaches the top and the bulk is the steady state; a
stream that ends below the top leaves its last particles, and with lags the
fine ones still waiting, in a band under the front).
Run from the repository root::

    python benchmarks/study_band3d.py --width 110 --height 480 --seeds 1 2 [--lag none]

``--shape sphere`` packs every phase as spheres.

``--lag none`` offers every particle at its turn (no pilot); the default learns
the lags with the pilot, as a scene does.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from regopack.api.functions import pack_and_summarise
from regopack.scenes.model import load_scene

SLABS = ((20.0, 60.0), (60.0, 100.0), (100.0, 150.0))
"""Heights over the floor (µm) whose density is compared with the bulk's."""
BULK_FROM = 150.0
BULK_UNDER_TOP = 120.0
SIDE_MARGIN = 20.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--width", type=float, default=110.0)
    parser.add_argument("--height", type=float, default=480.0)
    parser.add_argument("--seeds", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--lag", choices=["pilot", "none"], default="pilot")
    parser.add_argument("--count", type=int, default=20000)
    parser.add_argument("--shape", choices=["polyhedron", "sphere"], default="polyhedron")
    args = parser.parse_args()
    w, h = args.width, args.height
    # every phase of the scene as spheres (--shape sphere), or its polyhedra
    phases = load_scene("table1-3d").phases
    shapes = (
        {f"phases.{k}.shape": {"kind": "sphere"} for k in range(len(phases))}
        if args.shape == "sphere"
        else {}
    )
    rows = []
    for seed in args.seeds:
        started = time.perf_counter()
        out = pack_and_summarise(
            "table1-3d",
            seed=seed,
            count=args.count,
            verify=False,
            **{
                "domain.width": w,
                "domain.depth": w,
                "domain.height": h,
                "insertion.order": "sweep",
                "insertion.closing": "tail",
                "insertion.lag": args.lag,
                **shapes,
            },
        )
        p = out.packing
        c = p.centre[p.placed]
        fine = 2.0 * p.radius[p.placed] < 2.0 * math.sqrt(2.0)
        z = c[:, 2] + 0.5 * h  # the box is centred at the origin; height is the third axis
        inner = np.all(np.abs(c[:, :2]) < 0.5 * w - SIDE_MARGIN, axis=1)
        top = h - BULK_UNDER_TOP
        bulk = inner & (z > BULK_FROM) & (z < top)
        span = top - BULK_FROM
        row = []
        for a, b in SLABS:
            m = inner & (z > a) & (z < b)
            row.append(
                (
                    (np.sum(m) / (b - a)) / (np.sum(bulk) / span),
                    (np.sum(m & fine) / (b - a)) / (np.sum(bulk & fine) / span),
                )
            )
        rows.append(row)
        print(
            f"seed {seed}: {int(p.placed.sum())} placed in {time.perf_counter() - started:.1f} s"
            f" (pilot {out.summary.get('pilot_time_s', 0.0):.1f} s),"
            f" {int(np.sum(bulk & fine))} finest in the bulk;"
            + "".join(
                f"  {a:g}-{b:g} um: all {r[0]:.2f}, finest {r[1]:.2f}"
                for (a, b), r in zip(SLABS, row, strict=True)
            ),
            flush=True,
        )
    mean = np.mean(rows, axis=0)
    print(
        "mean:"
        + "".join(
            f"  {a:g}-{b:g} um: all {r[0]:.2f}, finest {r[1]:.2f}"
            for (a, b), r in zip(SLABS, mean, strict=True)
        )
    )


if __name__ == "__main__":
    main()

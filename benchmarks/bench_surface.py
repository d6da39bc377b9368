"""Packing speed of the available-surface inserter (3D) against the box size.

Packs a cube of side L of Table-1-like polyhedra (psi per mineral as in
Table 2, a = 1/3, sizes 2-12 µm so that small boxes hold many particles)
and prints one row per L: particles drawn and placed, phi over the box and
the interior window, time, analyses, and the exponent of time against N.
Each size runs in its own process after a warm-up that compiles the kernels.

    python benchmarks/bench_surface.py --sizes 30 45 60
    python benchmarks/bench_surface.py --sizes 45 60 --order sweep
    python benchmarks/bench_surface.py --sizes 45 60 --shape sphere

``--shape sphere`` packs the same scene with spheres of the same sizes.
``--height-ratio`` makes the box taller than wide; ``--closing`` and
``--strip`` (the width of the sweep's columns) pass to the inserter:

    python benchmarks/bench_surface.py --sizes 36 90 180 --order sweep --closing tail \
        --strip 45 --height-ratio 2
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys

import numpy as np

CHILD = r"""
import json, sys, time
import regopack
size = float(sys.argv[1]); seed = int(sys.argv[2]); order = sys.argv[3]; kind = sys.argv[4]
closing = sys.argv[5]; strip = float(sys.argv[6]); ratio = float(sys.argv[7])
phases = [
    ("pyroxene", 0.343, 0.25), ("feldspar", 0.315, 0.5), ("glass", 0.161, 1.0),
    ("olivine", 0.091, 2.0), ("ilmenite", 0.052, 15.0), ("others", 0.038, 0.8),
]
def shape(psi):
    return {"kind": "polyhedron", "psi": psi} if kind == "polyhedron" else {"kind": kind}
def scene(side, count="auto"):
    return {
        "name": "bench3d", "seed": seed, "count": count,
        "domain": {"kind": "box", "width": side, "height": ratio * side, "depth": side},
        "size": {"kind": "change5", "d_min": 2.0, "d_max": 12.0, "d0": 16.0, "alpha": 6.9},
        "phases": [{"name": n, "fraction": f, "shape": shape(p)} for n, f, p in phases],
        "insertion": {
            "kind": "available-surface", "order": order, "closing": closing, "strip": strip,
        },
        "density": {"kind": "eta"},
    }
regopack.pack(scene(20.0, 10), verify=False)  # compile or load the kernels
t = time.perf_counter()
out = regopack.pack_and_summarise(scene(size), verify=False)
s = out.summary
print(json.dumps({"L": size, "tried": s["tried"], "placed": s["placed"],
    "phi": s["phi_domain"], "phi_interior": s["phi_interior"],
    "time_s": s["insertion_time_s"], "analyses": s["candidate_analyses"],
    "empty": s["empty_analyses"]}))
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", type=float, nargs="+", default=[30.0, 45.0, 60.0])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--order", choices=["paper", "sweep"], default="paper")
    parser.add_argument("--shape", choices=["polyhedron", "sphere"], default="polyhedron")
    parser.add_argument("--closing", choices=["paced", "prompt", "tail"], default="paced")
    parser.add_argument("--strip", type=float, default=0.0, help="column width of the sweep")
    parser.add_argument("--height-ratio", type=float, default=1.0, help="box height / width")
    args = parser.parse_args()
    rows = []
    for size in args.sizes:
        out = subprocess.run(
            [
                sys.executable, "-c", CHILD, str(size), str(args.seed), args.order,
                args.shape, args.closing, str(args.strip), str(args.height_ratio),
            ],
            check=True, capture_output=True, text=True,
        )  # fmt: skip
        rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
    print(
        "| width (µm) | N drawn | placed | φ | φ interior | time (s) | ms per placed | analyses |"
    )
    print("|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(
            f"| {r['L']:g} | {r['tried']:,} | {r['placed']:,} | {r['phi']:.4f} | "
            f"{r['phi_interior']:.4f} | {r['time_s']:.1f} | "
            f"{1e3 * r['time_s'] / max(r['placed'], 1):.1f} | {int(r['analyses']):,} |"
        )
    if len(rows) >= 2:
        n = np.log([r["placed"] for r in rows])
        t = np.log([r["time_s"] for r in rows])
        slope = float(np.polyfit(n, t, 1)[0]) if np.ptp(n) > 0 else math.nan
        print(f"\nexponent of time against placed N: {slope:.2f}")


if __name__ == "__main__":
    main()

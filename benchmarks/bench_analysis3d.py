"""Time of the default 3D analyses against the number of particles.

Packs cubes of side L of Table-1-like polyhedra (the population of the asv
suite's 3D benchmarks: sizes 2-12 µm, psi per mineral as in Table 2), then
times each default analyzer (density, contacts, coordination, rdf, network)
on it, after a warm-up on a small box that loads the
compiled kernels and imports everything. Each size runs in its own process.
Prints one row per L and the exponent of the total time against N, with the
extrapolation to 10^4 particles. ``--figure`` copies the contact histograms
of the largest box (drawn by the package) to a file; ``--compile`` also
measures the cold compilation of the contact kernels (a fresh kernel cache).

    python benchmarks/bench_analysis3d.py --sizes 30 45 60 --figure fig.png
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

import numpy as np

CHILD = r"""
import json, shutil, sys, tempfile, time
from pathlib import Path
import regopack
from regopack.analysis.pipeline import DEFAULT_ANALYSES, run_analyses, write_analysis
from regopack.registry.manager import default_registry
size = float(sys.argv[1]); seed = int(sys.argv[2]); figure = sys.argv[3]
phases = [
    ("pyroxene", 0.343, 0.25), ("feldspar", 0.315, 0.5), ("glass", 0.161, 1.0),
    ("olivine", 0.091, 2.0), ("ilmenite", 0.052, 15.0), ("others", 0.038, 0.8),
]
def scene(side, count="auto"):
    return {
        "name": "bench3d", "seed": seed, "count": count,
        "domain": {"kind": "box", "width": side, "height": side, "depth": side},
        "size": {"kind": "change5", "d_min": 2.0, "d_max": 12.0, "d0": 16.0, "alpha": 6.9},
        "phases": [{"name": n, "fraction": f, "shape": {"kind": "polyhedron", "psi": p}}
                   for n, f, p in phases],
        "insertion": {"kind": "available-surface"}, "density": {"kind": "eta"},
    }
registry = default_registry()
small = regopack.pack(scene(30.0), verify=False)
run_analyses(small, registry, [(n, {}) for n in DEFAULT_ANALYSES])  # kernels and imports
t = time.perf_counter()
packing = regopack.pack(scene(size), verify=False)
pack_s = time.perf_counter() - t
times = {}
done = {}
for name in DEFAULT_ANALYSES:  # in the order of their requirements
    spec = registry.get("analysis", name)
    analyzer = spec.factory(spec.config_model())
    t = time.perf_counter()
    done[name] = analyzer.compute(packing, {r: done[r] for r in analyzer.requires})
    times[name] = time.perf_counter() - t
t = time.perf_counter()
analyzers = run_analyses(packing, registry, [(n, {}) for n in DEFAULT_ANALYSES])
total = time.perf_counter() - t
if figure != "-":
    with tempfile.TemporaryDirectory() as tmp:
        files = write_analysis(Path(tmp) / "a", packing, analyzers, registry=registry)
        shutil.copy(Path(tmp) / "a" / "figures" / "contact-histograms-3d.png", figure)
c = analyzers["coordination"].results()
print(json.dumps({"L": size, "placed": packing.n_placed, "pack_s": pack_s, "total_s": total,
    "times": times, "contacts": analyzers["contacts"].results()["n_contacts"],
    "pairs": analyzers["contacts"].results()["n_candidate_pairs"],
    "z_interior": c["z_interior"], "rattler_fraction": c["rattler_fraction"],
    "n_interior": c["n_interior"]}))
"""

COMPILE = r"""
import time
t = time.perf_counter()
from regopack.plugins.analyzers.contacts import Contacts
import sys; sys.path.insert(0, "tests/plugins/analyzers")
from lattices3d import cube_lattice
Contacts().compute(cube_lattice((2, 1, 1), (0.0, 0.0, 0.0)), {})
print(time.perf_counter() - t)
"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sizes", type=float, nargs="+", default=[30.0, 45.0, 60.0])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--figure", default=None, help="copy the largest box's contact histograms")
    parser.add_argument("--compile", action="store_true", help="time a cold kernel compilation")
    args = parser.parse_args()
    rows = []
    for k, size in enumerate(args.sizes):
        last = k == len(args.sizes) - 1
        figure = args.figure if (last and args.figure) else "-"
        out = subprocess.run(
            [sys.executable, "-c", CHILD, str(size), str(args.seed), figure],
            check=True, capture_output=True, text=True,
        )  # fmt: skip
        rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
        print(json.dumps(rows[-1]), file=sys.stderr)
    names = list(rows[0]["times"])
    head = " | ".join(names)
    print(f"| L (µm) | placed | pairs | contacts | Z interior | {head} | total (s) |")
    print("|---:" * (5 + len(names) + 1) + "|")
    for r in rows:
        cells = " | ".join(f"{r['times'][n]:.2f}" for n in names)
        print(
            f"| {r['L']:g} | {r['placed']:,} | {r['pairs']:,} | {r['contacts']:,} | "
            f"{r['z_interior']:.2f} | {cells} | {r['total_s']:.2f} |"
        )
    if len(rows) >= 2:
        n = np.log([r["placed"] for r in rows])
        t = np.log([r["total_s"] for r in rows])
        slope, icept = np.polyfit(n, t, 1) if np.ptp(n) > 0 else (math.nan, math.nan)
        print(f"\nexponent of the total time against placed N: {slope:.2f}")
        print(f"extrapolated to 10^4 particles: {math.exp(icept) * 1e4**slope:.1f} s")
    if args.compile:
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "NUMBA_CACHE_DIR": cache}
            out = subprocess.run(
                [sys.executable, "-c", COMPILE], check=True, capture_output=True, text=True,
                env=env,
            )  # fmt: skip
        print(f"cold compilation of the contact kernels: {float(out.stdout.strip()):.1f} s")


if __name__ == "__main__":
    main()

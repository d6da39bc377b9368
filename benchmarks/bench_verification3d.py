"""Time of the 3D oracle, regopack.verification3d.verify_polyhedra, on ~10^4 polyhedra.

The particles sit on a face-centred cubic lattice (4 m^3 sites); each is the
convex hull of 20 random points on the boundary of its Voronoi cell (a
rhombic dodecahedron), so neighbours nearly fill the space and their bounding
boxes overlap. Layouts:

* ``near``: every particle shrunk about its site by a random factor in
  [0.99, 0.999], so neighbours almost touch;
* ``touching``: not shrunk, so neighbours whose points fall on a shared
  face touch up to rounding (the case of a packing built by contact);
* ``overlapping``: grown by 1 %, so many neighbours overlap slightly.

Run from the repository root:

    python benchmarks/bench_verification3d.py --cells 14
    python benchmarks/bench_verification3d.py --cells 14 --periodic
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

from regopack.verification3d import verify_polyhedra

BASIS = np.array([(0, 0, 0), (1, 1, 0), (1, 0, 1), (0, 1, 1)], dtype=float)


def particles(cells: int, layout: str, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Vertices ``(n, 20, 3)``, and the sites, of the particles of a layout."""
    rng = np.random.default_rng(seed)
    grid = np.array(
        [(a, b, c) for a in range(cells) for b in range(cells) for c in range(cells)], dtype=float
    )
    sites = (2.0 * grid[:, None, :] + BASIS[None, :, :]).reshape(-1, 3)
    n = len(sites)
    u = rng.normal(size=(n, 20, 3))
    top2 = np.sort(np.abs(u), axis=2)[:, :, 1:].sum(axis=2)  # the cell is |x_i +- x_j| <= 1
    points = u / top2[:, :, None]
    if layout == "near":
        points *= rng.uniform(0.99, 0.999, size=(n, 1, 1))
    elif layout == "overlapping":
        points *= 1.01
    return points + sites[:, None, :], sites, np.full(3, 2.0 * cells)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--cells", type=int, default=14, help="FCC cells per side (4 m^3 sites)")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--periodic", action="store_true")
    args = parser.parse_args()
    print(f"machine: {platform.machine()}, CPython {platform.python_version()}")
    for layout in ("near", "touching", "overlapping"):
        verts, _, side = particles(args.cells, layout, args.seed)
        lo, hi = (np.zeros(3), side) if args.periodic else (np.full(3, -1.01), side + 0.01)
        started, cpu = time.perf_counter(), time.process_time()
        report = verify_polyhedra(verts, None, lo, hi, periodic=args.periodic)
        elapsed, cpu = time.perf_counter() - started, time.process_time() - cpu
        print(f"{layout:12s} n = {len(verts)}: {elapsed:6.2f} s wall, {cpu:6.2f} s CPU")
        print(f"    {report}")


if __name__ == "__main__":
    main()

"""Time `regopack.verification.verify` on a grid of touching particles.

Every pair of neighbours touches along a whole side (the hardest case for the
overlap test: no pair can be passed over by its distance). Run from the
repository root:

    python benchmarks/bench_verification.py --sizes 100 200 400
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from regopack.domain import Rectangle
from regopack.packing import Packing
from regopack.verification import verify


def grid(k: int) -> Packing:
    """``k * k`` touching unit squares, each outlined with 8 vertices."""
    n = k * k
    t = np.linspace(0, 1, 3)[:-1]
    edge = [np.c_[t, 0 * t], np.c_[1 + 0 * t, t], np.c_[1 - t, 1 + 0 * t], np.c_[0 * t, 1 - t]]
    local = np.concatenate(edge) - 0.5
    g = np.arange(k) + 0.5
    cx, cy = np.meshgrid(g, g)
    return Packing(
        radius=np.full(n, 1 / np.sqrt(np.pi)),
        mineral=np.zeros(n, dtype=np.int64),
        mineral_names=("a",),
        vertices=np.tile(local, (n, 1)),
        offsets=np.arange(0, 8 * n + 1, 8, dtype=np.int64),
        orientation=np.zeros(n),
        centre=np.c_[cx.ravel(), cy.ravel()],
        insertion_index=np.arange(n, dtype=np.int64),
        domain=Rectangle(0.0, float(k), 0.0, float(k)),
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 200, 400])
    args = parser.parse_args()
    verify(grid(10))  # imports and first calls
    print(f"{'particles':>10} {'verify (s)':>11} {'ok':>4}")
    for k in args.sizes:
        p = grid(k)
        start = time.perf_counter()
        report = verify(p)
        elapsed = time.perf_counter() - start
        print(f"{k * k:>10} {elapsed:>11.2f} {report.ok!s:>4}", flush=True)


if __name__ == "__main__":
    main()

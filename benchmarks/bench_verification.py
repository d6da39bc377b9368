"""Time `regopack.verification.verify` on a grid of touching particles.

Every pair of neighbours touches along a whole side (the hardest case for the
overlap test: no pair can be passed over by its distance). Run from the
repository root:

    python benchmarks/bench_verification.py --sizes 100 200 400
"""

from __future__ import annotations

import argparse
import time

from regopack.testing import touching_squares
from regopack.verification import verify


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 200, 400])
    args = parser.parse_args()
    verify(touching_squares(10))  # imports and first calls
    print(f"{'particles':>10} {'verify (s)':>11} {'ok':>4}")
    for k in args.sizes:
        p = touching_squares(k)
        start = time.perf_counter()
        report = verify(p)
        elapsed = time.perf_counter() - start
        print(f"{k * k:>10} {elapsed:>11.2f} {report.ok!s:>4}", flush=True)


if __name__ == "__main__":
    main()

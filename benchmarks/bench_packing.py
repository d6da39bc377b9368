"""Packing speed of the default (Table-1) scene against domain size.

Prints one row per domain side L: particles drawn and placed, packing time,
particles per second and peak memory, then the exponent of a power-law fit
of time against N. Run from the repository root:

    python benchmarks/bench_packing.py            # L = 200, 400, 800, 1600
    python benchmarks/bench_packing.py --sizes 200 400 800 1600 1965 --cold

``--cold`` also measures the very first run of the Table-1 scene in a fresh
process with an empty compilation cache (compilation included). Each size runs
in its own process so that peak memory is per run.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time

import numpy as np

CHILD = r"""
import json, resource, sys, time
t0 = time.perf_counter()
from regopack.manager import default_registry
from regopack.run import run_scene
from regopack.scene_model import load_scene, resolve_scene
overrides = json.loads(sys.argv[1])
warm = sys.argv[2] == "warm"
registry = default_registry()
if warm:  # compile (or load the cache) outside the timed run
    small = load_scene("table1", ["domain.width=60", "domain.height=60"])
    run_scene(resolve_scene(small, registry), None)
resolved = resolve_scene(load_scene("table1", overrides), registry)
t1 = time.perf_counter()
outcome = run_scene(resolved, None)
t2 = time.perf_counter()
s = outcome.summary
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
print(json.dumps({
    "tried": s["tried"], "placed": s["placed"], "phi_domain": s["phi_domain"],
    "phi_interior": s["phi_interior"], "pack_s": s.get("insert_time_s", t2 - t1),
    "run_s": t2 - t1, "process_s": t2 - t0, "peak_mb": peak,
    "analyses": s.get("candidate_analyses"), "empty": s.get("empty_analyses"),
}))
"""


def _child(overrides: list[str], warm: bool, env: dict[str, str] | None = None) -> dict[str, float]:
    out = subprocess.run(
        [sys.executable, "-c", CHILD, json.dumps(overrides), "warm" if warm else "cold"],
        check=True,
        capture_output=True,
        text=True,
        env=env,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])  # type: ignore[no-any-return]


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--sizes", type=float, nargs="+", default=[200, 400, 800, 1600])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--search", choices=["indexed", "linear"], default="indexed")
    parser.add_argument(
        "--cold", action="store_true", help="also time a first run with an empty cache"
    )
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="scene override for every size, as for 'regopack run --set' (repeatable)",
    )
    args = parser.parse_args()

    print(
        f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    )
    if args.overrides:
        print("overrides: " + " ".join(args.overrides))
    if args.cold:
        with tempfile.TemporaryDirectory() as cache:
            env = dict(os.environ, NUMBA_CACHE_DIR=cache)
            row = _child([f"seed={args.seed}"], warm=False, env=env)
        print(
            f"cold first run of table1 (compilation included): {row['process_s']:.1f} s "
            f"(packing {row['pack_s']:.2f} s)"
        )
    print(
        f"{'L':>6} {'N':>7} {'placed':>7} {'phi':>6} {'phi_int':>7} {'time_s':>7} "
        f"{'part/s':>8} {'peak_MB':>8} {'analyses':>9} {'empty%':>6}"
    )
    ns, ts = [], []
    for size in args.sizes:
        overrides = [
            f"domain.width={size}",
            f"domain.height={size}",
            f"seed={args.seed}",
            f'insertion.search="{args.search}"',
            *args.overrides,
        ]
        row = _child(overrides, warm=True)
        ns.append(row["tried"])
        ts.append(row["pack_s"])
        empty = 100.0 * row["empty"] / row["analyses"] if row.get("analyses") else float("nan")
        print(
            f"{size:6.0f} {row['tried']:7d} {row['placed']:7d} {row['phi_domain']:6.4f} "
            f"{row['phi_interior']:7.4f} {row['pack_s']:7.2f} {row['tried'] / row['pack_s']:8.0f} "
            f"{row['peak_mb']:8.0f} {row['analyses']:9.0f} {empty:6.1f}"
        )
    if len(ns) >= 2:
        slope = np.polyfit(np.log(ns), np.log(ts), 1)[0]
        print(f"fitted exponent of time against N: {slope:.3f}")


if __name__ == "__main__":
    started = time.perf_counter()
    main()
    print(f"benchmark wall time: {time.perf_counter() - started:.1f} s")

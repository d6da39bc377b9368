"""Cost of the structure analyses on the Table-1 packing.

Times each default analyzer (density, contacts, coordination, rdf, network) on
its own, all of them through ``regopack.analysis.run_analyses``, writing the
files (tables and report, then figures), and the cost of Z(tol) for one
tolerance against a sweep of 20. Run from the repository root:

    python benchmarks/bench_analysis.py                        # packs Table 1 first
    python benchmarks/bench_analysis.py --packing runs/table1-seed1/packing.npz

Compilation (or loading the compiled cache) happens in a warm-up on a small
packing before anything is timed; each time is the best of ``--repeat`` runs.
"""

from __future__ import annotations

import argparse
import os
import platform
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from regopack.analysis import DEFAULT_ANALYSES, run_analyses, write_analysis
from regopack.manager import default_registry
from regopack.packing import Packing, load
from regopack.plugins.analysis import (
    Contacts,
    ContactsConfig,
    Coordination,
    CoordinationConfig,
    Density,
    Network,
    Rdf,
)
from regopack.plugins.analysis.coordination import default_sweep
from regopack.run import run_scene
from regopack.scene_model import load_scene, resolve_scene


def best_of(repeat: int, fn: Callable[[], Any]) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def warm_up(registry: Any) -> None:
    small = resolve_scene(load_scene("table1", ["domain.width=80", "domain.height=80"]), registry)
    packing = run_scene(small).packing
    run_analyses(packing, registry, [(n, {}) for n in DEFAULT_ANALYSES])


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--packing", type=Path, help="analyse this packing instead of packing")
    parser.add_argument("--seed", type=int, default=1, help="seed of the Table-1 run")
    parser.add_argument("--repeat", type=int, default=3, help="runs per timing (best is kept)")
    args = parser.parse_args()
    started = time.perf_counter()
    registry = default_registry()
    print(
        f"machine: {platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, numpy {np.__version__}"
    )
    warm_up(registry)
    if args.packing is not None:
        packing: Packing = load(args.packing)
        source = str(args.packing)
    else:
        t0 = time.perf_counter()
        scene = resolve_scene(load_scene("table1", seed=args.seed), registry)
        packing = run_scene(scene).packing
        source = f"table1, seed {args.seed}, packed in {time.perf_counter() - t0:.1f} s"
    print(f"packing: {source}: {packing.n_placed:,} placed particles")

    contacts = Contacts().compute(packing, {})
    rows: list[tuple[str, float, str]] = []

    def add(label: str, fn: Callable[[], Any], note: str = "") -> float:
        seconds = best_of(args.repeat, fn)
        rows.append((label, seconds, note))
        return seconds

    add("density", lambda: Density().compute(packing, {}))
    add("contacts (tol 0.05, tol_max 0.5)", lambda: Contacts().compute(packing, {}))
    add(
        "coordination (given contacts)",
        lambda: Coordination().compute(packing, {"contacts": contacts}),
    )
    add("rdf (near + far, per mineral)", lambda: Rdf().compute(packing, {}))
    add("network (given contacts)", lambda: Network().compute(packing, {"contacts": contacts}))
    all_s = add(
        "all five, run_analyses",
        lambda: run_analyses(packing, registry, [(n, {}) for n in DEFAULT_ANALYSES]),
    )
    analyzers = run_analyses(packing, registry, [(n, {}) for n in DEFAULT_ANALYSES])
    with tempfile.TemporaryDirectory() as tmp:
        add(
            "write json + csv tables + report",
            lambda: write_analysis(Path(tmp), packing, analyzers, figures=False),
        )
        add(
            "write all, with 6 figures (PNG + SVG)",
            lambda: write_analysis(Path(tmp), packing, analyzers, figures=True),
        )

    # Z(tol): one tolerance against a sweep of 20 (the default 0.02-0.5)
    tol = 0.05
    sweep = default_sweep()

    def z_of(tols: list[float], tol_max: float) -> None:
        c = Contacts(ContactsConfig(tol=tol, tol_max=tol_max)).compute(packing, {})
        Coordination(CoordinationConfig(tols=tols)).compute(packing, {"contacts": c})

    one = add("Z(tol), 1 tolerance (tol_max = tol)", lambda: z_of([tol], tol))
    twenty = add(
        f"Z(tol), {len(sweep)} tolerances (tol_max = 0.5)", lambda: z_of(sweep, 0.5), "default"
    )
    add(
        f"Z(tol), {len(sweep)} tolerances given contacts",
        lambda: Coordination(CoordinationConfig(tols=sweep)).compute(
            packing, {"contacts": contacts}
        ),
        "coordination only",
    )

    width = max(len(r[0]) for r in rows)
    print(f"\n{'step':<{width}}  {'time (s)':>9}  note")
    print(f"{'-' * width}  {'-' * 9}  ----")
    for label, seconds, note in rows:
        print(f"{label:<{width}}  {seconds:>9.3f}  {note}")
    print(f"\nall default analyses: {all_s:.2f} s")
    print(f"Z(tol) for {len(sweep)} tolerances / for 1: {twenty / one:.2f}x")
    print(f"benchmark wall time: {time.perf_counter() - started:.1f} s")


if __name__ == "__main__":
    main()

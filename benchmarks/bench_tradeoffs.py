"""Speed against accuracy: one knob at a time from the defaults of the Table-1 scene.

For every setting of a knob, prints the insertion time, the packing fraction
of the domain, the interior coordination number Z (contacts at tol 0.05) and
the overlaps (number of overlapping pairs, worst relative area from
``regopack.verification.polygons.verify`` and worst penetration depth). Run from the
repository root:

    python benchmarks/bench_tradeoffs.py                       # L = 400, 1 seed
    python benchmarks/bench_tradeoffs.py --size 800 --seeds 1 2 3 --repeats 3
    python benchmarks/bench_tradeoffs.py --json tradeoffs.json --plot docs/images/tradeoffs.png

Knobs: the interference test (exact, or the paper's rule with tau), the
screening coefficient t, the octagon's number of edge directions m (all six
phases), the contact tolerance (analysis only, on the default packing), and
the needle-like particles of a = 1 under both interference tests.

Each setting runs in a fresh process, after a warm-up on a small domain with
the same settings so that compilation is not timed. With ``--repeats`` the
packing is timed that many times in the process and the minimum is kept
(other processes on the machine make single timings noisy).

The depth of an overlap is the equivalent thickness of the intersection of
the two outlines, ``2 × area / perimeter`` (exact for a long thin strip up to
the end caps); ``depth/r`` divides it by the equivalent radius of the smaller
particle of the pair.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

CHILD = r"""
import json, sys, time
import numpy as np
import shapely
from regopack.analysis.pipeline import run_analyses
from regopack.registry.manager import default_registry
from regopack.run.pipeline import run_scene
from regopack.scenes.model import load_scene, resolve_scene
from regopack.verification.polygons import verify

overrides, tol, repeats = json.loads(sys.argv[1]), float(sys.argv[2]), int(sys.argv[3])
registry = default_registry()
warm = [o for o in overrides if not o.startswith("domain.")]
small = load_scene("table1", warm + ["domain.width=60", "domain.height=60"])
run_scene(resolve_scene(small, registry), None)  # compile (or load the cache)
resolved = resolve_scene(load_scene("table1", overrides), registry)
times = []
for _ in range(repeats):
    outcome = run_scene(resolved, None)
    times.append(outcome.summary["wall_time_s"])
s, packing = outcome.summary, outcome.packing

params = {"contacts": {"tol": tol, "tol_max": tol}, "coordination": {"tols": [tol]}}
run_analyses(packing, registry, [("coordination", {})], params=params)  # warm-up
analysis_times = []
for _ in range(repeats):
    t0 = time.perf_counter()
    found = run_analyses(packing, registry, [("coordination", {})], params=params)
    analysis_times.append(time.perf_counter() - t0)
z = found["coordination"].results()

report = verify(packing)
depth, depth_rel = 0.0, 0.0
if report.n_overlapping_pairs:
    idx = np.flatnonzero(packing.placed)
    off = packing.offsets
    polys = np.array([shapely.Polygon(packing.vertices[off[i]:off[i + 1]] + packing.centre[i])
                      for i in idx], dtype=object)
    a, b = shapely.STRtree(polys).query(polys, predicate="intersects")
    a, b = a[a < b], b[a < b]
    inter = shapely.intersection(polys[a], polys[b])
    area = shapely.area(inter)
    smaller = np.minimum(shapely.area(polys[a]), shapely.area(polys[b]))
    bad = area > 1e-9 * smaller
    if bad.any():
        d = 2.0 * area[bad] / shapely.length(inter[bad])
        r = np.minimum(packing.radius[idx[a[bad]]], packing.radius[idx[b[bad]]])
        depth, depth_rel = float(d.max()), float((d / r).max())
print(json.dumps({
    "tried": s["tried"], "placed": s["placed"], "phi_domain": s["phi_domain"],
    "phi_interior": s["phi_interior"], "time_s": min(times),
    "analysis_s": min(analysis_times), "analyses": s.get("candidate_analyses"),
    "z_interior": z["z_interior"], "z_domain": z["z_domain"],
    "n_overlaps": report.n_overlapping_pairs,
    "worst_area": report.worst_overlap[2] if report.worst_overlap else 0.0,
    "worst_depth": depth, "worst_depth_rel": depth_rel,
}))
"""

PHASES = range(6)
COLLAPSED = 1000  # overlapping pairs beyond which a packing has collapsed


def _all_phases(key: str, value: object) -> list[str]:
    return [f"phases.{n}.shape.{key}={value}" for n in PHASES]


def knobs(quick: bool) -> dict[str, list[tuple[str, list[str], float]]]:
    """Knob name -> ``(setting label, overrides, contact tol)`` rows; defaults marked ``*``."""
    taus = [0.5, 0.65, 0.8] if quick else [0.5, 0.6, 0.65, 0.7, 0.8]
    interference = [("exact *", ['insertion.interference="exact"'], 0.05)] + [
        (f"tau {tau}", ['insertion.interference="tau"', f"insertion.tau={tau}"], 0.05)
        for tau in taus
    ]
    ts = [1.0, 0.999, 0.9] if quick else [1.0, 0.999, 0.99, 0.9]
    screening = [(f"t {t}" + (" *" if t == 0.999 else ""), [f"insertion.t={t}"], 0.05) for t in ts]
    ms = [6, 8, 16] if quick else [6, 8, 12, 16, 32]
    edges = [(f"m {m}" + (" *" if m == 8 else ""), _all_phases("m", m), 0.05) for m in ms]
    tols = [0.02, 0.05, 0.1, 0.2, 0.5]
    contact = [(f"tol {tol}" + (" *" if tol == 0.05 else ""), [], tol) for tol in tols]
    needles = [
        ("a 1, exact", _all_phases("a", 1.0), 0.05),
        ("a 1, tau 0.65", [*_all_phases("a", 1.0), 'insertion.interference="tau"'], 0.05),
    ]
    return {
        "interference": interference,
        "screening t": screening,
        "edges m": edges,
        "contact tol": contact,
        "a = 1": needles,
    }


def _child(overrides: list[str], tol: float, repeats: int) -> dict[str, Any]:
    out = subprocess.run(
        [sys.executable, "-c", CHILD, json.dumps(overrides), str(tol), str(repeats)],
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])  # type: ignore[no-any-return]


def _mean(rows: list[dict[str, Any]], key: str) -> float:
    return sum(float(r[key]) for r in rows) / len(rows)


def _merge(rows: list[dict[str, Any]]) -> dict[str, Any]:
    """One row per setting over seeds: minimum times, mean phi and Z, overlaps summed/worst."""
    return {
        "tried": _mean(rows, "tried"),
        "placed": _mean(rows, "placed"),
        "time_s": min(r["time_s"] for r in rows),
        "analysis_s": min(r["analysis_s"] for r in rows),
        "analyses": _mean(rows, "analyses"),
        "phi_domain": _mean(rows, "phi_domain"),
        "phi_interior": _mean(rows, "phi_interior"),
        "z_interior": _mean(rows, "z_interior"),
        "z_domain": _mean(rows, "z_domain"),
        "n_overlaps": sum(int(r["n_overlaps"]) for r in rows),
        "worst_area": max(r["worst_area"] for r in rows),
        "worst_depth": max(r["worst_depth"] for r in rows),
        "worst_depth_rel": max(r["worst_depth_rel"] for r in rows),
    }


def _print_table(knob: str, rows: list[dict[str, Any]]) -> None:
    analysis = knob == "contact tol"
    time_head = "anal_s" if analysis else "time_s"
    print(f"\n{knob}")
    print(
        f"{'setting':<15} {time_head:>7} {'analyses':>9} {'placed':>7} {'phi':>6} {'Z_int':>6} "
        f"{'overl':>6} {'worst_area':>10} {'depth_um':>8} {'depth/r':>7}"
    )
    for r in rows:
        t = r["analysis_s"] if analysis else r["time_s"]
        print(
            f"{r['setting']:<15} {t:7.3f} {r['analyses']:9.0f} {r['placed']:7.0f} "
            f"{r['phi_domain']:6.4f} {r['z_interior']:6.3f} {r['n_overlaps']:6d} "
            f"{r['worst_area']:10.2e} {r['worst_depth']:8.3f} {r['worst_depth_rel']:7.3f}"
        )


def plot(rows: list[dict[str, Any]], path: Path) -> None:
    """Small multiples: time against phi, Z and overlaps, one column per knob."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter

    present = {r["knob"] for r in rows}
    names = [k for k in ("interference", "screening t", "edges m", "contact tol") if k in present]
    metrics = [
        ("phi_domain", "φ (domain)"),
        ("z_interior", "Z (interior)"),
        ("n_overlaps", "overlapping pairs"),
    ]
    fig, axes = plt.subplots(len(metrics), len(names), figsize=(13, 8.5), squeeze=False)
    for col, knob in enumerate(names):
        sel = [r for r in rows if r["knob"] == knob]
        tkey = "analysis_s" if knob == "contact tol" else "time_s"
        xs = [r[tkey] for r in sel]
        for row, (key, label) in enumerate(metrics):
            ax = axes[row][col]
            if row == 0:
                ax.set_title(knob, fontsize=11)
            if col == 0:
                ax.set_ylabel(label)
            if knob == "contact tol" and key != "z_interior":
                ax.text(
                    0.5,
                    0.5,
                    "unchanged:\nthe tolerance only\naffects the analysis",
                    ha="center",
                    va="center",
                    transform=ax.transAxes,
                    fontsize=9,
                    color="0.4",
                )
                ax.set_xticks([])
                ax.set_yticks([])
                continue
            # a collapsed packing (thousands of overlaps) would flatten the phi and Z
            # axes: leave it out of them and say so
            shown = [
                (r, x)
                for r, x in zip(sel, xs, strict=True)
                if key == "n_overlaps" or r["n_overlaps"] <= COLLAPSED
            ]
            off = [
                f"{r['setting']}: {r[key]:.3g}"
                for r in sel
                if key != "n_overlaps" and r["n_overlaps"] > COLLAPSED
            ]
            if off:
                ax.text(
                    0.98,
                    0.95,
                    "off scale (collapsed)\n" + "\n".join(off),
                    ha="right",
                    va="top",
                    transform=ax.transAxes,
                    fontsize=8,
                    color="tab:purple",
                )
            ys = [r[key] for r, _ in shown]
            px = [x for _, x in shown]
            colours = ["tab:red" if r["setting"].endswith("*") else "tab:blue" for r, _ in shown]
            ax.scatter(px, ys, c=colours, s=30, zorder=3)
            for k, ((r, x), y) in enumerate(zip(shown, ys, strict=True)):
                ax.annotate(
                    r["setting"].rstrip(" *").split(" ")[-1],
                    (x, y),
                    textcoords="offset points",
                    xytext=(3, 5 if k % 2 == 0 else -12),
                    fontsize=8,
                )
            ax.grid(alpha=0.3)
            ax.margins(x=0.2, y=0.2)
            if key == "n_overlaps":
                ax.set_yscale("symlog", linthresh=1)
                ax.set_ylim(-0.3, max(10.0, 5.0 * max(ys)))
                ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
            if row == len(metrics) - 1:
                ax.set_xlabel(
                    "analysis time (s)" if knob == "contact tol" else "insertion time (s)"
                )
    fig.suptitle(
        "Table-1 scene, one knob at a time (red: default); time against φ, Z and overlaps",
        fontsize=12,
    )
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--size", type=float, default=400.0, help="domain side L (um)")
    parser.add_argument("--seeds", type=int, nargs="+", default=[1])
    parser.add_argument("--repeats", type=int, default=1, help="timings per process (min kept)")
    parser.add_argument("--quick", action="store_true", help="fewer settings per knob")
    parser.add_argument("--only", nargs="+", help="knobs to run (default: all)")
    parser.add_argument("--json", type=Path, help="write all rows to this file")
    parser.add_argument("--plot", type=Path, help="draw the small multiples to this file")
    parser.add_argument(
        "--load", type=Path, help="print and plot the rows of an earlier --json instead of running"
    )
    args = parser.parse_args()
    if args.load:
        loaded = json.loads(args.load.read_text(encoding="utf-8"))
        for knob in dict.fromkeys(r["knob"] for r in loaded):
            _print_table(knob, [r for r in loaded if r["knob"] == knob])
        if args.plot:
            plot(loaded, args.plot)
        return

    print(
        f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    )
    print(
        f"scene: table1, L = {args.size:g}, seeds {' '.join(map(str, args.seeds))}, "
        f"min of {args.repeats} timing(s); * marks the default"
    )
    all_rows: list[dict[str, Any]] = []
    for knob, settings in knobs(args.quick).items():
        if args.only and knob not in args.only:
            continue
        rows = []
        for label, overrides, tol in settings:
            per_seed = [
                _child(
                    [
                        f"domain.width={args.size}",
                        f"domain.height={args.size}",
                        f"seed={seed}",
                        *overrides,
                    ],
                    tol,
                    args.repeats,
                )
                for seed in args.seeds
            ]
            rows.append({"knob": knob, "setting": label, "tol": tol, **_merge(per_seed)})
        _print_table(knob, rows)
        all_rows.extend(rows)
    if args.json:
        args.json.write_text(json.dumps(all_rows, indent=1) + "\n", encoding="utf-8")
    if args.plot:
        plot(all_rows, args.plot)


if __name__ == "__main__":
    started = time.perf_counter()
    main()
    print(f"\nbenchmark wall time: {time.perf_counter() - started:.1f} s")

"""The sweep order against the paper's order, side by side, over several seeds.

For every seed the Table-1 scene is packed with ``insertion.order = "paper"``
(the reference) and with ``insertion.order = "sweep"`` (the scene ``dem``),
alternately in one process (paper, sweep, paper, sweep, ...) so that the drift
of the machine's speed affects both alike; a tiny packing of each order runs
first, so that compilation is not timed. Each packing is then measured by the
analyzers ``density``, ``contacts``, ``coordination``, ``rdf``,
``homogeneity`` and ``psd`` (default parameters, Z(tol) at 0.02, 0.05 and
0.5 µm). Prints a Markdown table of the mean ± standard deviation over the
seeds of each order and of the paired difference sweep − paper, then, for the
sweep, the mean diameter and number density in horizontal slabs of the
interior window. Run from the repository root:

    python benchmarks/compare_orders.py                      # seeds 1-9, L = 800
    python benchmarks/compare_orders.py --seeds 1 2 3 --size 400 --json orders.json

``--markdown FILE`` also writes the tables to FILE; ``--json FILE`` writes the
measurements of every run.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from regopack.analysis import run_analyses
from regopack.manager import Registry, default_registry
from regopack.packing import Packing
from regopack.plugins.analysis.common import interior_margin
from regopack.run import run_scene
from regopack.scene_model import load_scene, resolve_scene

ORDERS = ("paper", "sweep")
TOLS = (0.02, 0.05, 0.5)
FAR_TAIL_DMAX = 3.0
"""The far-field level is the mean of g(r) over the last this many d_max of the far field."""
SLABS = 8


def _requests() -> list[tuple[str, dict[str, Any]]]:
    return [
        ("density", {}),
        ("contacts", {}),
        ("coordination", {"tols": list(TOLS)}),
        ("rdf", {}),
        ("homogeneity", {}),
        ("psd", {}),
    ]


def _pack(
    order: str, seed: int, size: float, registry: Registry, extra: list[str] | None = None
) -> tuple[Packing, dict[str, Any]]:
    overrides = [
        f"domain.width={size}",
        f"domain.height={size}",
        f"seed={seed}",
        f'insertion.order="{order}"',
        *((extra or []) if order == "sweep" else []),
    ]
    resolved = resolve_scene(load_scene("table1", overrides), registry)
    outcome = run_scene(resolved, None)
    return outcome.packing, dict(outcome.summary)


def _analyse(packing: Packing, registry: Registry) -> tuple[dict[str, Any], list[str]]:
    """Run every analyzer; on a failure, run them one by one and report which failed."""
    errors: list[str] = []
    try:
        return run_analyses(packing, registry, _requests()), errors
    except Exception as err:  # reported, not hidden
        errors.append(f"all analyzers together: {type(err).__name__}: {err}")
    done: dict[str, Any] = {}
    for name, params in _requests():
        try:
            done.update(run_analyses(packing, registry, [(name, params)]))
        except Exception as err:  # reported, not hidden
            errors.append(f"{name}: {type(err).__name__}: {err}")
            traceback.print_exc()
    return done, errors


def _num(value: Any) -> float:
    return float(value) if value is not None else math.nan


def _measure(
    packing: Packing, summary: dict[str, Any], analyzers: dict[str, Any]
) -> dict[str, Any]:
    """The quantities of the table, for one packing (NaN where an analyzer is missing)."""
    row: dict[str, Any] = {
        "placed": summary["placed"],
        "tried": summary["tried"],
        "insert_time_s": summary["insert_time_s"],
        "refused": summary.get("refused", math.nan),
        "not_offered": summary.get("not_offered", math.nan),
        "candidate_analyses": summary.get("candidate_analyses", math.nan),
    }
    if "density" in analyzers:
        res = analyzers["density"].results()
        row["phi_domain"] = _num(res["phi_domain"])
        row["phi_interior"] = _num(res["phi_interior"])
    if "contacts" in analyzers:
        res = analyzers["contacts"].results()
        row["share_depth_below_tol"] = _num(res["share_depth_below_tol"])
        row["mean_depth_over_width"] = _num(res["mean_depth_over_width"])
    if "coordination" in analyzers:
        res = analyzers["coordination"].results()
        row["z_domain"] = _num(res["z_domain"])
        row["z_interior"] = _num(res["z_interior"])
        sweep = dict(zip(res["tol_sweep"], res["z_interior_sweep"], strict=True))
        for tol in TOLS:
            row[f"z_interior_tol_{tol:g}"] = _num(sweep.get(tol))
        for name, z in res["z_per_mineral"].items():
            row[f"z_{name}"] = _num(z)
    if "rdf" in analyzers:
        rdf = analyzers["rdf"]
        res = rdf.results()
        near, far = rdf.curves["near"], rdf.curves["far"]
        row["g_peak"] = float(np.nanmax(near["total"]))
        row["g_peak_r"] = _num(res["first_peak_r"])
        d_max = interior_margin(packing, None)
        r_hi = float(far["r"][-1] + 0.5 * (far["r"][1] - far["r"][0]))
        r_tail = max(_r_lo_far(far), r_hi - FAR_TAIL_DMAX * d_max)
        row["g_far_tail"] = float(np.nanmean(far["total"][far["r"] >= r_tail]))
        row["g_far_tail_range"] = [r_tail, r_hi]
        row["g_far_mean"] = _num(res["far_mean"])
        row["g_far_range"] = [_r_lo_far(far), r_hi]
    if "homogeneity" in analyzers:
        res = analyzers["homogeneity"].results()
        for key in (
            "density_slope_per_100",
            "density_slope_err",
            "mean_d_slope_per_100",
            "mean_d_slope_err",
            "density_max_rel_dev",
            "mean_d_max_rel_dev",
            "phi_max_rel_dev",
            "tile_density_max_rel_dev",
            "tile_mean_d_max_rel_dev",
            "tile_phi_max_rel_dev",
            "number_density",
            "mean_d",
            "ring_width",
            "n_rings",
        ):
            row[key] = _num(res[key])
    if "psd" in analyzers:
        res = analyzers["psd"].results()
        row["worst_number_rel_error"] = _num(res["worst_number_rel_error"])
        row["worst_mass_rel_error"] = _num(res["worst_mass_rel_error"])
        row["worst_number_class"] = res["worst_number_class"]
        row["worst_mass_class"] = res["worst_mass_class"]
        row["ks_number"] = _num(res["ks_number"])
    row["slabs"] = _slabs(packing)
    return row


def _r_lo_far(far: dict[str, Any]) -> float:
    """Lower edge of the far field's first bin."""
    return float(far["r"][0] - 0.5 * (far["r"][1] - far["r"][0]))


def _slabs(packing: Packing) -> dict[str, list[float]]:
    """Number density and mean diameter in horizontal slabs of the interior window."""
    window = packing.domain.interior(interior_margin(packing, None))
    x0, x1, y0, y1 = (float(b) for b in window.bounds())
    edges = np.linspace(y0, y1, SLABS + 1)
    sel = packing.placed & window.contains(packing.centre)
    y = packing.centre[sel, 1]
    d = 2.0 * packing.radius[sel]
    k = np.clip(np.searchsorted(edges, y, side="right") - 1, 0, SLABS - 1)
    n = np.bincount(k, minlength=SLABS).astype(np.float64)
    sum_d = np.bincount(k, weights=d, minlength=SLABS)
    area = (x1 - x0) * np.diff(edges)
    return {
        "y_lo": edges[:-1].tolist(),
        "y_hi": edges[1:].tolist(),
        "number_density": (n / area).tolist(),
        "mean_d": (sum_d / np.maximum(n, 1.0)).tolist(),
    }


# ---------------------------------------------------------------------------
# the table


def _stats(values: list[float]) -> tuple[float, float]:
    a = np.asarray(values, dtype=np.float64)
    a = a[np.isfinite(a)]
    if a.size == 0:
        return math.nan, math.nan
    return float(a.mean()), float(a.std(ddof=1)) if a.size > 1 else math.nan


def _pm(values: list[float], fmt: Callable[[float], str]) -> str:
    mean, sd = _stats(values)
    if not math.isfinite(mean):
        return "—"
    return fmt(mean) if not math.isfinite(sd) else f"{fmt(mean)} ± {fmt(sd)}"


def _signed(digits: int, scale: float = 1.0) -> Callable[[float], str]:
    def fmt(x: float) -> str:
        return f"{x * scale:.{digits}f}".replace("-", "−")

    return fmt


def _rows(runs: dict[str, list[dict[str, Any]]], minerals: list[str]) -> list[tuple[Any, ...]]:
    """(label, key, formatter, kind) per row; kind: 'diff', 'ratio', 'absmax' or 'sweep'."""
    pct = _signed(2, 100.0)
    rows: list[tuple[Any, ...]] = [
        ("placed", "placed", _signed(0), "diff"),
        ("φ domain", "phi_domain", _signed(4), "diff"),
        ("φ interior", "phi_interior", _signed(4), "diff"),
        ("Z domain (tol 0.05 µm)", "z_domain", _signed(3), "diff"),
        ("Z interior (tol 0.05 µm)", "z_interior", _signed(3), "diff"),
    ]
    for tol in TOLS:
        rows.append((f"Z interior, tol {tol:g} µm", f"z_interior_tol_{tol:g}", _signed(3), "diff"))
    rows += [
        ("share of contacts with δ < tol", "share_depth_below_tol", _signed(4), "diff"),
        ("mean δ / b_c", "mean_depth_over_width", _signed(4), "diff"),
    ]
    for name in minerals:
        rows.append((f"Z interior, {name}", f"z_{name}", _signed(3), "diff"))
    rows += [
        ("g(r) near-field peak height", "g_peak", _signed(2), "diff"),
        ("g(r) near-field peak position (µm)", "g_peak_r", _signed(2), "diff"),
        ("g(r) far-field level (tail)", "g_far_tail", _signed(4), "diff"),
        ("g(r) far-field mean, whole far field (`far_mean`)", "g_far_mean", _signed(4), "diff"),
        ("max over seeds of abs(g tail − 1)", "g_far_tail_dev", _signed(4), "absmax"),
        ("number density (10⁻³ µm⁻², window)", "number_density", _signed(3, 1e3), "diff"),
        ("mean diameter (µm, window)", "mean_d", _signed(3), "diff"),
        ("number density slope (10⁻³ µm⁻² per 100 µm)", "density_slope_per_100",
         _signed(3, 1e3), "diff"),
        ("  its fit error (same unit)", "density_slope_err", _signed(3, 1e3), "diff"),
        ("mean diameter slope (µm per 100 µm)", "mean_d_slope_per_100", _signed(3), "diff"),
        ("  its fit error (µm per 100 µm)", "mean_d_slope_err", _signed(3), "diff"),
        ("ring max rel. deviation, number density (%)", "density_max_rel_dev", pct, "diff"),
        ("  worst seed (%)", "density_max_rel_dev", pct, "absmax"),
        ("ring max rel. deviation, mean diameter (%)", "mean_d_max_rel_dev", pct, "diff"),
        ("  worst seed (%)", "mean_d_max_rel_dev", pct, "absmax"),
        ("ring max rel. deviation, φ (%)", "phi_max_rel_dev", pct, "diff"),
        ("tile max rel. deviation, number density (%)", "tile_density_max_rel_dev", pct, "diff"),
        ("tile max rel. deviation, mean diameter (%)", "tile_mean_d_max_rel_dev", pct, "diff"),
        ("tile max rel. deviation, φ (%)", "tile_phi_max_rel_dev", pct, "diff"),
        ("PSD worst class error by number (%)", "worst_number_rel_error", pct, "diff"),
        ("  worst seed, abs (%)", "worst_number_rel_error", pct, "absmax"),
        ("PSD worst class error by mass (%)", "worst_mass_rel_error", pct, "diff"),
        ("  worst seed, abs (%)", "worst_mass_rel_error", pct, "absmax"),
        ("PSD KS by number", "ks_number", _signed(4), "diff"),
        ("insertion time (s)", "insert_time_s", _signed(2), "ratio"),
        ("candidate analyses (10³)", "candidate_analyses", _signed(1, 1e-3), "diff"),
        ("refused", "refused", _signed(1), "sweep"),
        ("not offered", "not_offered", _signed(1), "sweep"),
    ]  # fmt: skip
    for order in ORDERS:
        for run in runs[order]:
            run["g_far_tail_dev"] = run.get("g_far_tail", math.nan) - 1.0
    return rows


def _worst(values: list[float], fmt: Callable[[float], str]) -> str:
    a = np.abs(np.asarray(values, dtype=np.float64))
    a = a[np.isfinite(a)]
    return fmt(float(a.max())) if a.size else "—"


def _table(runs: dict[str, list[dict[str, Any]]], minerals: list[str]) -> str:
    paper, sweep = runs["paper"], runs["sweep"]
    lines = [
        "| quantity | paper | sweep | sweep − paper |",
        "|---|---:|---:|---:|",
    ]
    for label, key, fmt, kind in _rows(runs, minerals):
        p = [r.get(key, math.nan) for r in paper]
        s = [r.get(key, math.nan) for r in sweep]
        if kind == "absmax":
            lines.append(f"| {label} | {_worst(p, fmt)} | {_worst(s, fmt)} | |")
            continue
        if kind == "sweep":
            lines.append(f"| {label} | | {_pm(s, fmt)} | |")
            continue
        if kind == "ratio":
            ratio = [b / a for a, b in zip(p, s, strict=True)]
            diff = f"× {_pm(ratio, _signed(2))}"
        else:
            diff = _pm([b - a for a, b in zip(p, s, strict=True)], fmt)
        lines.append(f"| {label} | {_pm(p, fmt)} | {_pm(s, fmt)} | {diff} |")
    return "\n".join(lines)


def _slab_table(sweep: list[dict[str, Any]]) -> str:
    dens = np.array([r["slabs"]["number_density"] for r in sweep])
    mean_d = np.array([r["slabs"]["mean_d"] for r in sweep])
    lo, hi = sweep[0]["slabs"]["y_lo"], sweep[0]["slabs"]["y_hi"]
    all_dens = float(dens.mean())
    all_d = float(np.mean([r["mean_d"] for r in sweep]))
    sd = 1 if len(sweep) > 1 else 0
    lines = [
        "| slab, centre height y (µm) | number density (10⁻³ µm⁻²) | dev. | "
        "mean diameter (µm) | dev. |",
        "|---|---:|---:|---:|---:|",
    ]
    for k in range(len(lo)):
        dn, dd = dens[:, k], mean_d[:, k]
        cells = (
            f"{lo[k]:.0f} to {hi[k]:.0f}",
            f"{1e3 * dn.mean():.2f} ± {1e3 * dn.std(ddof=sd):.2f}",
            f"{100 * (dn.mean() / all_dens - 1):+.1f} %",
            f"{dd.mean():.3f} ± {dd.std(ddof=sd):.3f}",
            f"{100 * (dd.mean() / all_d - 1):+.1f} %",
        )
        lines.append(("| " + " | ".join(cells) + " |").replace("-", "−"))
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--seeds", type=int, nargs="+", default=list(range(1, 10)))
    parser.add_argument("--size", type=float, default=800.0, help="domain side L (µm)")
    parser.add_argument("--markdown", type=Path, help="also write the tables to this file")
    parser.add_argument("--json", type=Path, help="write every run's measurements here")
    parser.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="scene override for the sweep runs only, e.g. insertion.closing=prompt (repeatable)",
    )
    args = parser.parse_args()

    started = time.perf_counter()
    registry = default_registry()
    head = (
        f"machine: {platform.machine()}, {os.cpu_count()} cores, "
        f"Python {platform.python_version()}, numpy {np.__version__}\n"
        f'scene: table1 (paper) and table1 with insertion.order = "sweep" (= dem), '
        f"L = {args.size:g} µm, seeds {' '.join(map(str, args.seeds))}"
    )
    print(head, flush=True)
    for order in ORDERS:  # compile (or load the cache) outside the timed runs
        packing, _ = _pack(order, 1, 60.0, registry, args.set)
        _analyse(packing, registry)
    runs: dict[str, list[dict[str, Any]]] = {order: [] for order in ORDERS}
    failures: list[str] = []
    minerals: list[str] = []
    for seed in args.seeds:
        for order in ORDERS:
            packing, summary = _pack(order, seed, args.size, registry, args.set)
            t0 = time.perf_counter()
            analyzers, errors = _analyse(packing, registry)
            analysis_s = time.perf_counter() - t0
            for err in errors:
                failures.append(f"seed {seed}, {order}: {err}")
                print(f"ANALYSIS FAILED: seed {seed}, {order}: {err}", flush=True)
            row = _measure(packing, summary, analyzers)
            row["seed"], row["analysis_s"] = seed, analysis_s
            minerals = list(packing.mineral_names)
            runs[order].append(row)
            print(
                f"seed {seed} {order:5s}: placed {row['placed']:6d}  "
                f"phi_int {row.get('phi_interior', math.nan):.4f}  "
                f"insert {row['insert_time_s']:6.2f} s  analyses {analysis_s:5.1f} s",
                flush=True,
            )

    tail = runs["paper"][0].get("g_far_tail_range", [math.nan, math.nan])
    far = runs["paper"][0].get("g_far_range", [math.nan, math.nan])
    table = _table(runs, minerals)
    slabs = _slab_table(runs["sweep"])
    notes = [
        f"Mean ± standard deviation over {len(args.seeds)} seed(s); the last column is the mean ± "
        "standard deviation of the paired difference (same seed, same population), for the time "
        "the ratio sweep / paper.",
        f"g(r) far-field level, tail: mean of the total g(r) over r in [{tail[0]:g}, {tail[1]:g}] "
        f"µm (the last {FAR_TAIL_DMAX:g} d_max of the rdf analyzer's default far field, 2 µm "
        f"bins); `far_mean` is the analyzer's mean over its whole far field, [{far[0]:g}, "
        f"{far[1]:g}] µm.",
    ]
    out = "\n".join(
        [
            head,
            "",
            table,
            "",
            *notes,
            "",
            f"Sweep, {SLABS} horizontal slabs of the interior window by centre height "
            "(mean ± sd over seeds; dev. from the mean over the window):",
            "",
            slabs,
        ]
    )
    if failures:
        out += "\n\nAnalyzer failures:\n" + "\n".join(f"- {f}" for f in failures)
    print()
    print(out)
    if args.markdown:
        args.markdown.write_text(out + "\n", encoding="utf-8")
    if args.json:
        args.json.write_text(json.dumps(runs, indent=1, default=float), encoding="utf-8")
    print(f"\nbenchmark wall time: {time.perf_counter() - started:.1f} s")


if __name__ == "__main__":
    main()

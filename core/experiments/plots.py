"""Plots of a finished sweep, chosen by what its ``results.csv`` holds.

:func:`plot_experiment` reads ``results.csv`` and ``experiment.json`` of a sweep
and writes into ``<out>/plots/`` (PNG and SVG):

- ``phi_vs_eta``: φ (and Z, when collected) against η, mean ± SD over the
  seeds, one line per value of the other varied fields, with the first η at
  which the voids connect across the interior window marked (when the runs
  have ``voids.void_spans``; see :mod:`regopack.packing.voids`);
- ``seeds`` and ``table3.md``: φ and Z of every seed with their mean ± SD, and
  a Markdown table of mean, SD and coefficient of variation (SD / mean);
- ``time_vs_n``: insertion time against the number of particles on log-log
  axes, one line per ``insertion.t`` and ``insertion.search``, with the fitted
  power-law exponent in the legend.

Lines, legend entries and the sections of ``table3.md`` follow the values of
the other varied fields, numbers by value (η = 5 before η = 10) and before
any text.
"""

from __future__ import annotations

import csv
import json
import math
import shutil
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.ticker import MaxNLocator, NullFormatter

from regopack.base.outdir import rebase, replace_folder

__all__ = ["PLOTS_DIR", "fit_power_law", "plot_experiment", "seed_statistics"]

PLOTS_DIR = "plots"
"""Folder of the plots inside the sweep's output directory."""

PLOTS_KIND = "plots"
"""Kind of the plots folder (in its marker file)."""

_COLOURS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000")
_MARKERS = ("o", "s", "^", "D", "v", "P", "X")
_DPI = 200

_PHI = ("phi_interior", "analyses.density.phi_interior", "phi_domain")
_Z = ("analyses.coordination.z_interior", "analyses.coordination.z_domain")
_TIME = ("insertion_time_s", "insert_time_s", "wall_time_s")
"""Time columns, best first: the first one holds the insertion without compilation."""


def _float(text: str | None) -> float:
    if text is None or text == "":
        return math.nan
    if text in ("true", "false"):
        return 1.0 if text == "true" else 0.0
    try:
        return float(text)
    except ValueError:
        return math.nan


def _read(out_dir: Path) -> tuple[list[str], list[dict[str, str]]]:
    """Read the varied fields and the finished rows of a sweep."""
    with (out_dir / "results.csv").open(newline="", encoding="utf-8") as fh:
        rows = [row for row in csv.DictReader(fh) if row.get("status") == "done"]
    params: list[str] = []
    try:
        data = json.loads((out_dir / "experiment.json").read_text(encoding="utf-8"))
        params = [str(p) for p in data.get("parameters", [])]
    except (OSError, json.JSONDecodeError):
        pass
    return params, rows


def _first(rows: Sequence[Mapping[str, str]], names: Sequence[str]) -> str | None:
    """Return the first column of ``names`` that has a value in some row."""
    for name in names:
        if any(row.get(name, "") != "" for row in rows):
            return name
    return None


def _short(param: str) -> str:
    return param.rsplit(".", 1)[-1]


def _group_label(params: Sequence[str], key: tuple[str, ...]) -> str:
    if not params:
        return ""
    parts: list[str] = []
    seen: set[str] = set()
    for p, v in zip(params, key, strict=True):
        text = f"{_short(p)} = {v}"
        if text in seen:  # e.g. the same psi for every mineral: say it once
            continue
        seen.add(text)
        parts.append(text)
    return ", ".join(parts)


def _groups(
    rows: Sequence[dict[str, str]], params: Sequence[str]
) -> dict[tuple[str, ...], list[dict[str, str]]]:
    out: dict[tuple[str, ...], list[dict[str, str]]] = {}
    for row in rows:
        out.setdefault(tuple(row.get(p, "") for p in params), []).append(row)
    return out


def _value_order(text: str) -> tuple[int, float, str]:
    """Sort key of one cell: numbers by value, before any other text (sorted as text)."""
    try:
        number = float(text)
    except ValueError:
        return (1, 0.0, text)
    return (1, 0.0, text) if math.isnan(number) else (0, number, text)


def _sorted_groups(
    rows: Sequence[dict[str, str]], params: Sequence[str]
) -> list[tuple[tuple[str, ...], list[dict[str, str]]]]:
    """:func:`_groups` ordered field by field, numeric values by value (5 before 10).

    Examples
    --------
    >>> rows = [{"eta": e} for e in ("10", "0", "5", "auto")]
    >>> [key for key, _ in _sorted_groups(rows, ["eta"])]
    [('0',), ('5',), ('10',), ('auto',)]
    """
    groups = _groups(rows, params)
    return sorted(groups.items(), key=lambda item: tuple(_value_order(v) for v in item[0]))


@contextmanager
def _figure(ncols: int = 1) -> Iterator[Any]:
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    with plt.rc_context(
        {"font.size": 9, "axes.grid": True, "grid.alpha": 0.3, "legend.fontsize": 7.5}
    ):
        fig, axes = plt.subplots(1, ncols, figsize=(4.6 * ncols, 3.6), squeeze=False)
        try:
            yield fig, list(axes[0])
        finally:
            plt.close(fig)


def _save(fig: Any, plots: Path, stem: str) -> list[Path]:
    plots.mkdir(parents=True, exist_ok=True)
    fig.tight_layout()
    paths = []
    for fmt in ("png", "svg"):
        path = plots / f"{stem}.{fmt}"
        fig.savefig(path, format=fmt, dpi=_DPI)
        paths.append(path)
    return paths


def _mean_sd(values: Sequence[float]) -> tuple[float, float]:
    arr = np.asarray([v for v in values if not math.isnan(v)], dtype=float)
    if arr.size == 0:
        return math.nan, math.nan
    sd = float(arr.std(ddof=1)) if arr.size > 1 else 0.0
    return float(arr.mean()), sd


def fit_power_law(n: Sequence[float], time: Sequence[float]) -> tuple[float, float]:
    """Fit ``time = c · n^k`` by least squares in log-log space; return ``(k, c)``.

    Examples
    --------
    >>> k, c = fit_power_law([10, 100, 1000], [2.0, 20.0, 200.0])
    >>> round(k, 6), round(c, 6)
    (1.0, 0.2)
    """
    x = np.log(np.asarray(n, dtype=float))
    y = np.log(np.asarray(time, dtype=float))
    k, log_c = np.polyfit(x, y, 1)
    return float(k), float(math.exp(log_c))


def _plot_eta(params: list[str], rows: list[dict[str, str]], plots: Path) -> list[Path]:
    phi = _first(rows, _PHI)
    if phi is None:
        return []
    z = _first(rows, _Z)
    others = [p for p in params if p not in ("density.eta", "seed")]
    with _figure(2 if z else 1) as (fig, axes):
        for k, (key, group) in enumerate(_sorted_groups(rows, others)):
            colour, marker = _COLOURS[k % len(_COLOURS)], _MARKERS[k % len(_MARKERS)]
            by_eta = _groups(group, ["density.eta"])
            etas = sorted(by_eta, key=lambda e: _float(e[0]))
            x = np.array([_float(e[0]) for e in etas])
            label = _group_label(others, key) or None
            for ax, column in zip(axes, [phi, z], strict=False):
                if column is None:
                    continue
                stats = [_mean_sd([_float(r.get(column)) for r in by_eta[e]]) for e in etas]
                mean = np.array([s[0] for s in stats])
                sd = np.array([s[1] for s in stats])
                ax.errorbar(
                    x,
                    mean,
                    yerr=sd,
                    color=colour,
                    marker=marker,
                    ms=4,
                    lw=1.2,
                    capsize=2,
                    label=label,
                )
            spans = [
                _mean_sd([_float(r.get("voids.void_spans")) for r in by_eta[e]])[0] for e in etas
            ]
            first = next((i for i, s in enumerate(spans) if s >= 0.5), None)
            if any(not math.isnan(s) for s in spans):
                for ax in axes:
                    if first is not None:
                        ax.axvline(x[first], color=colour, ls="--", lw=0.9)
                if first is not None:
                    phi_at = _mean_sd([_float(r.get(phi)) for r in by_eta[etas[first]]])[0]
                    axes[0].plot(
                        [x[first]],
                        [phi_at],
                        marker="*",
                        ms=13,
                        color=colour,
                        mec="black",
                        mew=0.6,
                        ls="none",
                        label=f"voids connect (η = {x[first]:g})" if not others else None,
                    )
        axes[0].set_xlabel("packing control coefficient η")
        axes[0].set_ylabel(f"packing density φ ({'interior' if 'interior' in phi else 'domain'})")
        axes[0].set_title("φ against η (mean ± SD over seeds)")
        if z is not None:
            axes[1].set_xlabel("packing control coefficient η")
            axes[1].set_ylabel(f"coordination number Z ({_short(z).split('_')[-1]})")
            axes[1].set_title("Z against η")
        if "voids.void_spans" in rows[0]:
            any_span = any(_float(r.get("voids.void_spans")) == 1.0 for r in rows)
            note = (
                "★ / dashed: first η whose largest void spans the window"
                if any_span
                else "voids never span the interior window at these η"
            )
            fractions = [_float(r.get("voids.largest_void_fraction")) for r in rows]
            if not all(math.isnan(f) for f in fractions):
                largest = float(np.nanmax(fractions))
                note += f"\n(largest void ≤ {100 * largest:.2g} % of the window)"
            axes[0].text(
                0.02,
                0.05,
                note,
                transform=axes[0].transAxes,
                fontsize=7,
                color="#333333",
                bbox={"boxstyle": "round,pad=0.2", "facecolor": "white", "alpha": 0.85, "lw": 0},
            )
        handles, _ = axes[0].get_legend_handles_labels()
        if handles:
            axes[0].legend(loc="best")
        return _save(fig, plots, "phi_vs_eta")


def seed_statistics(
    rows: Sequence[Mapping[str, str]], columns: Sequence[str]
) -> dict[str, tuple[float, float, float]]:
    """Mean, sample SD and coefficient of variation (SD / mean) of each column.

    Examples
    --------
    >>> stats = seed_statistics([{"phi": "0.8"}, {"phi": "0.9"}], ["phi"])
    >>> [round(v, 4) for v in stats["phi"]]
    [0.85, 0.0707, 0.0832]
    """
    out: dict[str, tuple[float, float, float]] = {}
    for column in columns:
        mean, sd = _mean_sd([_float(r.get(column)) for r in rows])
        cv = sd / mean if mean and not math.isnan(mean) else math.nan
        out[column] = (mean, sd, cv)
    return out


def _plot_seeds(params: list[str], rows: list[dict[str, str]], plots: Path) -> list[Path]:
    columns = [c for c in (*_PHI[:1], _PHI[2], _Z[0], _Z[1]) if _first(rows, [c])]
    if not columns:
        return []
    others = [p for p in params if p != "seed"]
    groups = _sorted_groups(rows, others)
    lines = ["# Repeatability over seeds", ""]
    for key, group in groups:
        label = _group_label(others, key)
        if label:
            lines += [f"## {label}", ""]
        lines += [
            f"{len(group)} seeds.",
            "",
            "| quantity | mean | SD | CV (%) |",
            "| --- | ---: | ---: | ---: |",
        ]
        for column, (mean, sd, cv) in seed_statistics(group, columns).items():
            lines.append(f"| `{column}` | {mean:.4f} | {sd:.4f} | {100 * cv:.3f} |")
        lines.append("")
    plots.mkdir(parents=True, exist_ok=True)
    table = plots / "table3.md"
    table.write_text("\n".join(lines), encoding="utf-8")
    shown = [c for c in (_first(rows, _PHI), _first(rows, _Z)) if c is not None]
    if len(groups) > len(_COLOURS) // 2:  # too many lines to read: the table says it all
        return [table]
    with _figure(len(shown)) as (fig, axes):
        for ax, column in zip(axes, shown, strict=True):
            for k, (key, group) in enumerate(groups):
                colour = _COLOURS[k % len(_COLOURS)]
                seeds = np.array([_float(r.get("seed")) for r in group])
                values = np.array([_float(r.get(column)) for r in group])
                mean, sd = _mean_sd(list(values))
                ax.plot(seeds, values, "o", color=colour, ms=5, label=_group_label(others, key))
                ax.axhline(mean, color=colour, lw=1.2)
                ax.axhspan(mean - sd, mean + sd, color=colour, alpha=0.15)
                ax.text(
                    0.02,
                    0.95 - 0.08 * k,
                    f"mean {mean:.4f} ± {sd:.4f} (CV {100 * sd / mean:.2f} %)",
                    transform=ax.transAxes,
                    fontsize=7.5,
                    color=colour,
                    va="top",
                )
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
            ax.set_xlabel("seed")
            ax.set_ylabel(column.rsplit(".", 1)[-1])
            ax.set_title(("φ" if "phi" in column else "Z") + " over seeds: mean ± SD band")
            ax.margins(y=0.35)
        paths = _save(fig, plots, "seeds")
    return [table, *paths]


def _plot_time(params: list[str], rows: list[dict[str, str]], plots: Path) -> list[Path]:
    time = _first(rows, _TIME)
    n_col = _first(rows, ("placed", "tried"))
    if time is None or n_col is None:
        return []
    others = [p for p in params if p not in ("domain.width", "domain.height", "seed")]
    with _figure() as (fig, axes):
        ax = axes[0]
        for k, (key, group) in enumerate(_sorted_groups(rows, others)):
            n = np.array([_float(r.get(n_col)) for r in group])
            t = np.array([_float(r.get(time)) for r in group])
            keep = (n > 0) & (t > 0) & np.isfinite(n) & np.isfinite(t)
            n, t = n[keep], t[keep]
            if n.size == 0:
                continue
            order = np.argsort(n)
            n, t = n[order], t[order]
            values = dict(zip(others, key, strict=True))
            linear = values.get("insertion.search") == "linear"
            colour = _COLOURS[k % len(_COLOURS)]
            label = _group_label(others, key) or "runs"
            if np.unique(n).size >= 2:
                exponent, c = fit_power_law(n, t)
                grid = np.geomspace(n.min(), n.max(), 50)
                ax.plot(grid, c * grid**exponent, color=colour, lw=1, ls=":" if linear else "-")
                label += f": N^{exponent:.2f}"
            ax.plot(
                n,
                t,
                _MARKERS[k % len(_MARKERS)],
                color=colour,
                ms=5,
                mfc="white" if linear else colour,
                label=label,
            )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel(f"particles ({n_col})")
        ax.set_ylabel(f"time (s, {time})")
        ax.set_title("time against N, fitted power laws")
        ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
        fig.set_size_inches(7.8, 3.8)
        return _save(fig, plots, "time_vs_n")


def plot_experiment(out_dir: str | Path) -> list[Path]:
    """Draw the plots the results of a sweep allow; return the files written.

    Parameters
    ----------
    out_dir
        The sweep's output directory (with ``results.csv`` and ``experiment.json``).
        The plots go into ``<out_dir>/plots/``, which is written as a whole
        (see :func:`regopack.base.outdir.replace_folder`): it holds the plots of
        this call and none of an earlier one.

    Returns
    -------
    list of Path
        The files written (none when the results fit no plot).
    """
    out = Path(out_dir)
    params, rows = _read(out)
    if not rows:
        return []
    plots = out / PLOTS_DIR
    written: list[Path] = []
    with replace_folder(plots, PLOTS_KIND) as tmp:
        if "density.eta" in params:
            written += _plot_eta(params, rows, tmp)
        seeds = {row.get("seed") for row in rows}
        if "seed" in params and len(seeds) >= 2:
            written += _plot_seeds(params, rows, tmp)
        if "domain.width" in params:
            written += _plot_time(params, rows, tmp)
    if not written:  # nothing to plot: no folder, and none left of an earlier call
        shutil.rmtree(plots, ignore_errors=True)
    return [rebase(p, tmp, plots) for p in written]

"""Figure of the psd analyzer: percent passing, class shares and errors, placed vs requested."""

from __future__ import annotations

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.ticker import LogLocator, NullFormatter, ScalarFormatter

from regopack.plugins.analyzers.figure_style import TOTAL, WIDTH
from regopack.plugins.analyzers.psd import Psd

__all__ = ["draw_psd"]

PLACED = "#D55E00"
ANALYTIC = "#0072B2"


def _log_d_axis(ax: Axes, lo: float, hi: float, unit: str = "µm") -> None:
    ax.set_xscale("log")
    ax.set_xlim(lo, hi)
    ax.xaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    ax.xaxis.set_major_formatter(ScalarFormatter())
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel(f"equivalent diameter d ({unit})")


def _passing(ax: Axes, psd: Psd) -> None:
    """Cumulative percent finer than d, from the particles themselves (exact steps)."""
    d, mass, placed = psd.diameter, psd.mass, psd.placed
    for sel, colour in ((np.ones(len(d), bool), TOTAL), (placed, PLACED)):
        for w, style in ((np.ones(len(d)), "-"), (mass, "--")):
            order = np.argsort(d[sel], kind="stable")
            ds, ws = d[sel][order], w[sel][order]
            if ds.size == 0 or not ws.sum() > 0:
                continue
            pct = 100.0 * np.cumsum(ws) / ws.sum()
            ax.step(np.r_[ds[0], ds], np.r_[0.0, pct], where="post", color=colour, ls=style)
    if psd.cdf is not None:
        grid = np.geomspace(float(psd.classes["d_lo"][0]), float(psd.classes["d_hi"][-1]), 400)
        f = psd.cdf(grid)
        cell = (0.5 * (grid[:-1] + grid[1:])) ** psd.mass_power * np.maximum(np.diff(f), 0.0)
        by_mass = np.r_[0.0, np.cumsum(cell)]
        for y, style in ((f, "-"), (by_mass / by_mass[-1] if by_mass[-1] > 0 else by_mass, "--")):
            ax.plot(grid, 100.0 * y, color=ANALYTIC, ls=style, lw=0.8, alpha=0.9)
    ax.set_ylim(0.0, 100.0)
    ax.set_ylabel("percent finer than d (%)")
    ax.set_title("percent passing")


def _shares(ax: Axes, psd: Psd, basis: str) -> None:
    c = psd.classes
    edges = np.r_[c["d_lo"][0], c["d_hi"]]
    drawn = 100.0 * np.nan_to_num(c[f"{basis}_share_drawn"])
    placed = 100.0 * np.nan_to_num(c[f"{basis}_share_placed"])
    ax.stairs(drawn, edges, fill=True, color="#cccccc", label="requested (all drawn)")
    ax.stairs(drawn, edges, color=TOTAL, lw=0.6)
    ax.stairs(placed, edges, color=PLACED, lw=1.2, label="placed")
    if psd.cdf is not None:
        mid = np.sqrt(edges[:-1] * edges[1:])
        ax.plot(
            mid,
            100.0 * c[f"{basis}_share_analytic"],
            ls="none",
            marker="o",
            ms=2.5,
            mfc="white",
            color=ANALYTIC,
            label="size distribution",
        )
    ax.set_ylim(0.0, None)
    ax.set_ylabel(f"{basis} share per class (%)")
    measure = " (area)" if psd.mass_power == 2 else " (volume)"
    ax.set_title(f"√2 classes by {basis}" + (measure if basis == "mass" else ""))


def _errors(ax: Axes, psd: Psd, basis: str) -> None:
    """Relative error of each class's share, placed against requested, with the tolerance band."""
    c, res = psd.classes, psd.results()
    tol = float(res["tolerance"])
    rel = 100.0 * np.asarray(c[f"{basis}_rel_error"], dtype=np.float64)
    checked = np.asarray(c["checked"], dtype=bool)
    shown = np.abs(rel[checked & np.isfinite(rel)])
    lim = 1.25 * max(200.0 * tol, float(shown.max()) if shown.size else 0.0, 1.0)
    mid = np.sqrt(c["d_lo"] * c["d_hi"])
    ax.axhspan(-100.0 * tol, 100.0 * tol, color="#e5e5e5", lw=0)
    ax.axhline(0.0, color=TOTAL, lw=0.6)
    y = np.clip(np.nan_to_num(rel, nan=0.0), -lim, lim)
    chance = 200.0 * np.nan_to_num(np.asarray(c[f"{basis}_rel_error_sampling"], dtype=np.float64))
    ax.errorbar(mid, y, yerr=chance, ls="none", color="#777777", elinewidth=0.7, capsize=0)
    for sel, face in ((checked, PLACED), (~checked, "white")):
        ax.plot(mid[sel], y[sel], ls="none", marker="o", ms=3.5, color=PLACED, mfc=face)
    ax.set_ylim(-lim, lim)
    ax.set_ylabel("placed / requested − 1 (%)", fontsize=7)
    ax.set_title(f"class error by {basis}")


def _verdict(ax: Axes, psd: Psd, unit: str) -> None:
    """Write the classes held to the tolerance, in words, beside the error panels."""
    res = psd.results()
    ax.axis("off")
    pct = 100.0 * float(res["tolerance"])
    lines = [
        f"{res['n_classes_checked']} classes with ≥ {res['min_class_count']} drawn",
        "(filled markers);",
        f"{res['n_classes_within']} of them within ±{pct:g} % (shaded)",
        "by number and by mass;",
        "bars: ± 2 σ of the error of a",
        "random subset of the drawn.",
        "",
    ]
    for basis in ("number", "mass"):
        worst, where = res[f"worst_{basis}_rel_error"], res[f"worst_{basis}_class"]
        if worst is not None:
            lines.append(f"worst by {basis}: {100.0 * worst:+.2f} %")
            lines.append(f"    in [{where[0]:.3g}, {where[1]:.3g}) {unit}")
    text = ax.text(0.0, 1.0, "\n".join(lines), transform=ax.transAxes, va="top", ha="left")
    text.set_in_layout(False)


def draw_psd(psd: Psd, unit: str = "µm") -> Figure:
    """Percent passing, class shares and class errors by number and mass, placed against requested.

    Diameters are labelled in ``unit``, the packing's length unit. Under the
    class shares, the relative error of each class's share with the tolerance
    band; the classes held to it are filled.
    """
    fig = Figure(figsize=(WIDTH, 4.6))
    grid = fig.subplot_mosaic(
        [["passing", "number", "mass"], ["verdict", "number_error", "mass_error"]],
        height_ratios=[1.6, 1.0],
    )
    axes = [grid["passing"], grid["number"], grid["mass"]]
    c = psd.classes
    if len(c.get("class", [])) == 0 or psd.diameter.size == 0:
        for ax in grid.values():
            ax.axis("off")
        for ax in axes:
            ax.text(0.5, 0.5, "no particles", transform=ax.transAxes, ha="center")
        return fig
    lo, hi = float(c["d_lo"][0]), float(c["d_hi"][-1])
    _passing(axes[0], psd)
    _shares(axes[1], psd, "number")
    _shares(axes[2], psd, "mass")
    _errors(grid["number_error"], psd, "number")
    _errors(grid["mass_error"], psd, "mass")
    _verdict(grid["verdict"], psd, unit)
    for ax in (*axes, grid["number_error"], grid["mass_error"]):
        _log_d_axis(ax, lo, hi, unit)
    handles = [
        Line2D([], [], color=TOTAL, label="requested (all drawn)"),
        Line2D([], [], color=PLACED, label="placed"),
        Line2D([], [], color="#555555", ls="-", label="by number"),
        Line2D([], [], color="#555555", ls="--", label="by mass"),
    ]
    if psd.cdf is not None:
        kind = psd.results().get("analytic")
        handles.append(
            Line2D(
                [],
                [],
                color=ANALYTIC,
                lw=0.8,
                marker="o",
                ms=2.5,
                mfc="white",
                label=f"size distribution ({kind})",
            )
        )
    res = psd.results()
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles), columnspacing=1.5)
    fig.suptitle(
        f"{res['n_placed']:,} of {res['n_drawn']:,} particles placed; "
        f"KS distance placed vs requested: {res['ks_number'] or 0:.3g} by number, "
        f"{res['ks_mass'] or 0:.3g} by mass",
        fontsize=8,
    )
    return fig

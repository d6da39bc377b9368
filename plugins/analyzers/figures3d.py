"""Figures of the 3D analyzers, drawn with matplotlib at the size and style of the 2D ones.

``contact-histograms-3d`` (``contacts3d``): A_c, V_c, b_c and the cap height δ;
``z-vs-tol-3d`` and ``z-per-mineral-3d`` (``coordination3d``): the 2D figures
on the 3D contacts; ``rdf-3d`` (``rdf3d``): g(r) of all centres and of each
mineral with itself, near and far field; ``psd-3d`` (``psd3d``): the 2D
size-distribution figure, with masses as volumes; ``homogeneity-3d``
(``homogeneity3d``): number density, φ and mean diameter over the horizontal
layers and the nested shells of the interior window.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, cast

import numpy as np
from matplotlib.figure import Figure

from regopack.base.colours import mineral_colours
from regopack.base.units import decimals, length_scale, length_unit
from regopack.plugins.analyzers.contacts3d import Contacts3D
from regopack.plugins.analyzers.coordination3d import Coordination3D
from regopack.plugins.analyzers.figure_specs import STEMS3D
from regopack.plugins.analyzers.figures import (
    TOTAL,
    WIDTH,
    _log_hist,
    _note,
    _save,
    _style,
    draw_binned,
    draw_z_per_mineral,
    draw_z_vs_tol,
    legend_entries,
    mark_first_peak,
    note_single_bins,
)
from regopack.plugins.analyzers.homogeneity3d import Homogeneity3D
from regopack.plugins.analyzers.psd3d import Psd3D
from regopack.plugins.analyzers.rdf3d import Rdf3D
from regopack.registry.interfaces import Analyzer

__all__ = ["draw_contact_histograms3d", "draw_homogeneity3d", "draw_rdf3d", "figures3d_for"]


def draw_contact_histograms3d(contacts: Contacts3D) -> Figure:
    """Histograms of A_c, V_c, b_c and the cap height δ, log-spaced bins on log axes."""
    fig = Figure(figsize=(WIDTH, 4.6))
    axes = fig.subplots(2, 2)
    tol = contacts.tol
    u = length_unit(contacts.packing)
    panels = (
        (contacts.area, rf"contact area $A_\mathrm{{c}}$ ({u}², projected)", f"{u}²"),
        (contacts.volume, rf"contact volume $V_\mathrm{{c}}$ ({u}³)", f"{u}³"),
        (contacts.width, rf"contact width $b_\mathrm{{c}}$ ({u})", u),
        (contacts.depth, rf"cap height $\delta$ ({u})", u),
    )
    for ax, (values, label, unit) in zip(axes.ravel(), panels, strict=True):
        _log_hist(ax, values, label, unit)
    if contacts.depth.size:
        ax_d = axes[1, 1]
        ax_d.axvline(tol, color="#D55E00", linewidth=0.9, label=f"tol = {tol:g} {u}")
        ax_d.axvline(
            2 * tol, color="#D55E00", linestyle=":", linewidth=0.9, label="2 tol (face to face)"
        )
    for ax in axes.ravel():
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper left")
    fig.suptitle(f"{len(contacts.area):,} contacts at tol = {tol:g} {u}", fontsize=8)
    return fig


def draw_homogeneity3d(homogeneity: Homogeneity3D, unit: str = "µm") -> Figure:
    """Draw number density, φ and mean diameter over the layers (top) and shells (bottom).

    Each region is drawn at its middle (the layer's height, the shell's mean
    half width), with a dashed line at the mean over the regions; lengths are
    labelled in ``unit``.
    """
    fig = Figure(figsize=(WIDTH, 4.4))
    axes = fig.subplots(2, 3)
    rows = (
        (homogeneity.layers, "z_lo", "z_hi", f"height z of the layer ({unit})"),
        (homogeneity.shells, "half_lo", "half_hi", f"half width of the shell ({unit})"),
    )
    columns = (
        ("density", f"number density (1/{unit}³)"),
        ("phi", "volume fraction φ"),
        ("mean_diameter", f"mean diameter ({unit})"),
    )
    for row, (table, lo, hi, xlabel) in enumerate(rows):
        x = 0.5 * (np.asarray(table[lo]) + np.asarray(table[hi]))
        for col, (key, ylabel) in enumerate(columns):
            ax = axes[row, col]
            y = np.asarray(table[key], dtype=float)
            if x.size:
                ax.plot(x, y, marker="o", markersize=3, linewidth=0.9, color="#0072B2")
                finite = y[np.isfinite(y)]
                if finite.size:
                    mean = float(finite.mean())
                    ax.axhline(mean, color="0.4", linestyle="--", linewidth=0.7)
                    spread = float(finite.std() / mean) if mean else float("nan")
                    ax.set_title(f"mean {mean:.4g}, spread {100 * spread:.1f} %", fontsize=7)
            else:
                _note(ax, "no interior window")
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
    fig.suptitle(
        "Homogeneity of the interior window: layers along z, shells about the centre", fontsize=8
    )
    return fig


def draw_rdf3d(packing: Any, rdf: Rdf3D) -> Figure:
    """g(r) of all interior centres and of each mineral with itself, near and far field."""
    names = packing.mineral_names
    colours = mineral_colours(names)
    unit = length_unit(packing)
    places = decimals(length_scale(packing), 2)
    res = rdf.results()
    fig = Figure(figsize=(WIDTH, 3.0))
    axes = fig.subplots(1, 2)
    for ax, key, title in zip(axes, ("near", "far"), ("near field", "far field"), strict=True):
        curves = rdf.curves.get(key)
        if curves is None:
            _note(ax, f"no {title} (window too small)")
            continue
        r = curves["r"]
        step = float(r[1] - r[0]) if len(r) > 1 else 0.0
        pairs = rdf.pair_curves.get(key, {})
        single = []
        for name, colour in zip(names, colours, strict=True):
            curve = pairs.get(f"{name}-{name}")
            label = f"{name}–{name}"
            if curve is not None and not draw_binned(
                ax, curve, step, color=colour, linewidth=0.8, label=label
            ):
                single.append(label)
        note_single_bins(ax, single)
        ax.plot(r, curves["total"], color=TOTAL, linewidth=1.2, label="all particles")
        ax.axhline(1.0, color="#777777", linestyle=":", linewidth=0.7)
        mark_first_peak(ax, rdf.peak if key == "near" else None, unit, places)
        ax.set_xlim(float(r[0]) - 0.5 * step, float(r[-1]) + 0.5 * step)
        ax.set_xlabel(f"centre distance r ({unit})")
        ax.set_ylabel("g(r)")
        ax.set_title(f"{title}, bins of {step:g} {unit}")
    handles, labels = legend_entries(axes, [*(f"{n}–{n}" for n in names), "all particles"])
    if handles:
        fig.legend(
            handles,
            labels,
            loc="outside lower center",
            ncol=min(len(handles), 4),
            title=f"{res['n_points']:,} interior centres; window "
            + " × ".join(f"{s:g}" for s in res["window"])
            + f" {unit} (a rare mineral's bins merged: steps over the merged bins)",
            title_fontsize=7,
        )
    return fig


def figures3d_for(
    packing: Any,
    analyzers: Mapping[str, Analyzer],
    out_dir: str | Path,
    *,
    formats: Sequence[str] = ("png", "svg"),
    of: str | None = None,
) -> list[Path]:
    """Draw the figures of the computed 3D analyzers; return the files written.

    Parameters
    ----------
    packing
        The analysed 3D packing.
    analyzers
        Computed analyzers by name; figures are drawn for ``contacts3d``,
        ``coordination3d``, ``rdf3d``, ``psd3d`` and ``homogeneity3d``.
    out_dir
        Directory of the figures (created if needed).
    formats
        File formats to write.
    of
        Draw only the figures of this analyzer (see
        :data:`~regopack.plugins.analyzers.figure_specs.STEMS3D`); by default all.
    """
    out = Path(out_dir)
    contacts = analyzers.get("contacts3d")
    contacts = contacts if isinstance(contacts, Contacts3D) else None
    coordination = analyzers.get("coordination3d")
    rdf = analyzers.get("rdf3d")
    jobs: list[tuple[str, Callable[[], Figure]]] = []
    if contacts is not None:
        jobs.append(("contact-histograms-3d", lambda: draw_contact_histograms3d(contacts)))
    if isinstance(coordination, Coordination3D):
        # the 2D figures read the counts, thresholds and masks that 3D contacts also have
        as_2d = cast(Any, contacts)
        jobs.append(("z-vs-tol-3d", lambda: draw_z_vs_tol(packing, coordination, as_2d)))
        jobs.append(("z-per-mineral-3d", lambda: draw_z_per_mineral(packing, coordination)))
    if isinstance(rdf, Rdf3D):
        jobs.append(("rdf-3d", lambda: draw_rdf3d(packing, rdf)))
    psd = analyzers.get("psd3d")
    if isinstance(psd, Psd3D):
        from regopack.plugins.analyzers.psd_figure import draw_psd

        jobs.append(("psd-3d", lambda: draw_psd(psd, length_unit(packing))))
    homogeneity = analyzers.get("homogeneity3d")
    if isinstance(homogeneity, Homogeneity3D):
        unit = length_unit(packing)
        jobs.append(("homogeneity-3d", lambda: draw_homogeneity3d(homogeneity, unit)))
    if of is not None:
        jobs = [(stem, draw) for stem, draw in jobs if stem in STEMS3D.get(of, ())]
    if not jobs:
        return []
    out.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    with _style():
        for stem, draw in jobs:
            paths += _save(draw(), out, stem, formats)
    return paths

"""Figures of the structure analysis, drawn with matplotlib off screen.

:func:`figures_for` draws the figures whose analyzers were computed and saves
each as PNG (300 dpi) and SVG; those of a 3D packing end in ``-3d``:

==========================  ==================  ==============================================
file stem                   needs               shows (figure of the paper)
==========================  ==================  ==============================================
``packing``                 ``density``         particles coloured by mineral, zoom (10)
``contact-network``         ``network``         centre-to-centre edges, width ∝ A_c (12)
``contact-histograms[-3d]`` ``contacts``        A_c, b_c, R_c, δ on log axes (13); 3D: A_c, V_c,
                                                b_c and the cap height δ
``z-vs-tol[-3d]``           ``coordination``    Z against tol, full range and zoom (14)
``z-per-mineral[-3d]``      ``coordination``    distribution of Z per mineral (15)
``rdf[-3d]``                ``rdf``             g(r) per mineral, near and far field (16); 3D:
                                                each mineral with itself
``homogeneity[-3d]``        ``homogeneity``     ring profiles with trends, tile maps; 3D:
                                                layers and shells
``psd[-3d]``                ``psd``             percent passing, class shares
``local-fraction``          ``local_fraction``  map of local φ per particle, histogram
==========================  ==================  ==============================================

Figures are sized for a journal page (7 in wide, 8 pt text, see
:mod:`~regopack.plugins.analyzers.figure_style`) and colour the minerals by
name from one colour-blind-safe palette (Okabe and Ito; see
:mod:`regopack.base.colours`), so a mineral keeps its colour in every scene.
Lengths are labelled in the scene's ``length_unit`` (micrometres by default).
Collections with many items are rasterised inside the SVG files to keep them
small; axes and text stay vector.
"""

from __future__ import annotations

import textwrap
from collections.abc import Callable, Collection, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.ticker import LogLocator, MaxNLocator, NullFormatter
from numpy.typing import NDArray

from regopack.base.colours import PALETTE, mineral_colours
from regopack.base.units import decimals, length_scale, length_unit
from regopack.packing.core import Packing
from regopack.plugins.analyzers.contacts import Contacts
from regopack.plugins.analyzers.coordination import Coordination
from regopack.plugins.analyzers.density import Density
from regopack.plugins.analyzers.figure_style import (
    DPI,
    RASTERISE_ABOVE,
    TOTAL,
    WIDTH,
    frame,
    in_window,
    length_text,
    link_zoom,
    nice_length,
    note,
    save,
    style,
    zoom_size,
    zoom_window,
)
from regopack.plugins.analyzers.homogeneity import Homogeneity
from regopack.plugins.analyzers.local_fraction import LocalFraction
from regopack.plugins.analyzers.network import Network
from regopack.plugins.analyzers.psd import Psd
from regopack.plugins.analyzers.rdf import Rdf
from regopack.plugins.analyzers.rdf_peak import BinnedCurve, PeakFit, count_bins, merge_bins
from regopack.registry.interfaces import Analyzer

__all__ = [
    "DPI",
    "PALETTE",
    "WIDTH",
    "draw_binned",
    "figures_for",
    "legend_entries",
    "length_text",
    "mark_first_peak",
    "mineral_colours",
    "nice_length",
]

FloatArray = NDArray[np.float64]


MAX_LINE_PT = 2.5
"""Line width, in points, of the contact with the largest A_c in the network figure."""

ZOOM_TOL = (0.02, 0.1)
"""Range of tol of the zoom of ``z-vs-tol`` at the built-in scale (``d_min = 2``): ``d_min / 100``
to ``d_min / 20``, times :func:`~regopack.base.units.length_scale` for other packings."""

_AC = r"$A_\mathrm{c}$"

NOTE_WIDTH = 36
"""Characters per line of the notes written inside a panel."""

Z_BARS_WIDTH = 0.8
"""Width, in units of Z, of the group of bars (one per mineral) at each value of Z."""


# ---------------------------------------------------------------------------
# helpers


def _polygons(
    packing: Packing, idx: NDArray[np.int64], colours: Sequence[str], **kwargs: Any
) -> PolyCollection:
    faces = np.asarray(colours, dtype=object)[packing.mineral[idx]]
    coll = PolyCollection(packing.polygons(idx), closed=True, facecolors=list(faces), **kwargs)
    coll.set_rasterized(len(idx) > RASTERISE_ABOVE)
    return coll


def _mineral_legend(fig: Figure, packing: Packing, colours: Sequence[str]) -> None:
    counts = np.bincount(packing.mineral[packing.placed], minlength=len(packing.mineral_names))
    handles = [
        Patch(facecolor=c, edgecolor="#333333", linewidth=0.4, label=f"{name} ({counts[k]:,})")
        for k, (name, c) in enumerate(zip(packing.mineral_names, colours, strict=False))
    ]
    fig.legend(
        handles=handles,
        loc="outside lower center",
        ncol=min(len(handles), 6),
        handlelength=1.2,
        columnspacing=1.2,
    )


def _title(packing: Packing) -> str:
    dom = packing.domain
    name = packing.scene.get("name", "packing")
    return (
        f"{name}, seed {packing.seed}: {packing.n_placed:,} particles, "
        f"{length_text(dom.width)} × {length_text(dom.height)} {length_unit(packing)}"
    )


# ---------------------------------------------------------------------------
# the figures


def draw_packing(packing: Packing) -> Figure:
    """Fig. 10: the packing coloured by mineral, and a zoomed view of its centre."""
    colours = mineral_colours(packing.mineral_names)
    unit = length_unit(packing)
    dom = packing.domain
    fig = Figure(figsize=(WIDTH, 4.0))
    ax, zoom = fig.subplots(1, 2)
    placed = np.flatnonzero(packing.placed).astype(np.int64)
    ax.add_collection(_polygons(packing, placed, colours, linewidths=0.0))
    frame(ax, dom.bounds().tolist(), unit, length_scale(packing))
    ax.set_title(_title(packing))
    window = zoom_window(packing)
    near = in_window(packing, window)
    zoom.add_collection(_polygons(packing, near, colours, edgecolors="#222222", linewidths=0.3))
    frame(zoom, window, unit, length_scale(packing))
    zoom.set_title(f"zoom: {zoom_size(window, unit)} at the centre")
    link_zoom(fig, ax, zoom, window, "black")
    _mineral_legend(fig, packing, colours)
    return fig


def _edge_widths(area: FloatArray) -> FloatArray:
    top = float(area.max()) if area.size else 0.0
    return MAX_LINE_PT * area / top if top > 0 else np.zeros_like(area)


def draw_network(packing: Packing, contacts: Contacts) -> Figure:
    """Fig. 12: contacts as centre-to-centre lines of width ∝ A_c, full domain and zoom."""
    dom = packing.domain
    unit = length_unit(packing)
    fig = Figure(figsize=(WIDTH, 3.9))
    ax, zoom = fig.subplots(1, 2)
    i, j, area = contacts.i, contacts.j, contacts.area
    segments = np.stack([packing.centre[i], packing.centre[j]], axis=1)
    widths = _edge_widths(area)
    window = zoom_window(packing)
    x0, x1, y0, y1 = window
    mid = 0.5 * (segments[:, 0] + segments[:, 1])
    inside = (mid[:, 0] > x0) & (mid[:, 0] < x1) & (mid[:, 1] > y0) & (mid[:, 1] < y1)
    near = in_window(packing, window)
    zoom.add_collection(
        PolyCollection(
            packing.polygons(near),
            facecolors="#f4f4f4",
            edgecolors="#b4b4b4",
            linewidths=0.3,
        )
    )
    # the zoom uses its own scale (thickest visible contact = MAX_LINE_PT) so that
    # its contacts stay readable; the factor is printed in its title
    top_zoom = float(area[inside].max()) if inside.any() else 0.0
    factor = float(area.max()) / top_zoom if top_zoom > 0 else 1.0
    for target, sel, scale in (
        (ax, np.ones(len(area), dtype=bool), 1.0),
        (zoom, inside, factor),
    ):
        lines = LineCollection(
            list(segments[sel]),
            linewidths=scale * widths[sel],
            colors="#08306b",
            capstyle="round",
        )
        lines.set_rasterized(int(sel.sum()) > RASTERISE_ABOVE)
        target.add_collection(lines)
    frame(ax, dom.bounds().tolist(), unit, length_scale(packing))
    frame(zoom, window, unit, length_scale(packing))
    ax.set_title(f"{len(area):,} contacts at tol = {contacts.tol:g} {unit}")
    widths_note = f" (widths × {factor:.2g})" if factor > 1.05 else ""
    zoom.set_title(f"zoom, {zoom_size(window, unit)} at the centre{widths_note}")
    link_zoom(fig, ax, zoom, window, "#D55E00")
    if len(area):
        top = float(area.max())
        handles = [
            Line2D(
                [],
                [],
                color="#08306b",
                linewidth=MAX_LINE_PT * f,
                label=f"{_AC} = {f * top:.2g} {unit}²",
            )
            for f in (1.0, 0.5, 0.1)
        ]
        fig.legend(
            handles=handles,
            loc="outside lower center",
            ncol=3,
            handlelength=2.5,
            title="line width, whole domain (width ∝ contact area)",
            title_fontsize=7,
        )
    else:
        note(ax, "no contacts")
    return fig


def _log_hist(ax: Axes, values: FloatArray, label: str, unit: str, colour: str = "#0072B2") -> None:
    v = values[np.isfinite(values) & (values > 0)]
    if v.size == 0:
        note(ax, "no contacts")
        ax.set_xlabel(label)
        return
    lo, hi = float(v.min()), float(v.max())
    if hi <= lo:
        lo, hi = lo / 1.5, hi * 1.5
    bins = np.geomspace(lo, hi, 41)
    counts, _ = np.histogram(v, bins=bins)
    ax.stairs(counts, bins, fill=True, baseline=0.5, color=colour, alpha=0.85)
    ax.stairs(counts, bins, baseline=0.5, color="#08306b", linewidth=0.5)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylim(0.5, None)
    ax.xaxis.set_major_locator(LogLocator(base=10, numticks=8))
    for axis in (ax.xaxis, ax.yaxis):  # few, unlabelled minor ticks: faster to lay out
        axis.set_minor_locator(LogLocator(base=10, subs=(2.0, 5.0), numticks=12))
        axis.set_minor_formatter(NullFormatter())
    med = float(np.median(v))
    ax.axvline(med, color="black", linestyle="--", linewidth=0.8, label=f"median {med:.3g} {unit}")
    ax.set_xlabel(label)
    ax.set_ylabel("contacts per bin")


def draw_contact_histograms(contacts: Contacts) -> Figure:
    """Fig. 13: histograms of the contact sizes, with log-spaced bins on log axes.

    A_c, b_c, R_c and δ of 2D contacts; A_c, V_c, b_c and the cap height δ of 3D ones.
    """
    fig = Figure(figsize=(WIDTH, 4.6))
    axes = fig.subplots(2, 2)
    tol = contacts.tol
    u = length_unit(contacts.packing)
    solid = contacts.packing.domain.dimension == 3
    if solid:
        panels = (
            (contacts.area, rf"contact area $A_\mathrm{{c}}$ ({u}², projected)", f"{u}²"),
            (contacts.volume, rf"contact volume $V_\mathrm{{c}}$ ({u}³)", f"{u}³"),
            (contacts.width, rf"contact width $b_\mathrm{{c}}$ ({u})", u),
            (contacts.depth, rf"cap height $\delta$ ({u})", u),
        )
    else:
        panels = (
            (contacts.area, f"contact area {_AC} ({u}²)", f"{u}²"),
            (contacts.width, rf"contact width $b_\mathrm{{c}}$ ({u})", u),
            (contacts.radius, rf"segment radius $R_\mathrm{{c}}$ ({u})", u),
            (contacts.depth, rf"segment depth $\delta$ ({u})", u),
        )
    for ax, (values, label, unit) in zip(axes.ravel(), panels, strict=True):
        _log_hist(ax, values, label, unit)
    if contacts.depth.size:
        face = 2 if solid else 1.5  # the depth of two faces touching at tol
        ax_d = axes[1, 1]
        ax_d.axvline(tol, color="#D55E00", linewidth=0.9, label=f"tol = {tol:g} {u}")
        ax_d.axvline(
            face * tol,
            color="#D55E00",
            linestyle=":",
            linewidth=0.9,
            label=f"{face:g} tol (face to face)",
        )
    for ax in axes.ravel():
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="upper left")
    fig.suptitle(f"{len(contacts.area):,} contacts at tol = {tol:g} {u}", fontsize=8)
    return fig


def _exact_z_of_tol(
    packing: Packing, contacts: Contacts, lo: float, hi: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Z(tol) over ``[lo, hi]`` as exact step curves (domain and interior)."""
    order = np.argsort(contacts.threshold, kind="stable")
    thr = contacts.threshold[order]
    pairs = contacts.pairs[order]
    interior = contacts.interior
    n_dom = max(packing.n_placed, 1)
    n_int = max(int(interior.sum()), 1)
    w_int = interior[pairs[:, 0]].astype(np.float64) + interior[pairs[:, 1]]
    cum_dom = 2.0 * np.arange(1, len(thr) + 1) / n_dom
    cum_int = np.cumsum(w_int) / n_int
    keep = (thr > lo) & (thr < hi)
    start = int(np.searchsorted(thr, lo, side="right"))
    z0_dom = 2.0 * start / n_dom
    z0_int = float(cum_int[start - 1]) if start > 0 else 0.0
    t = np.concatenate([[lo], thr[keep], [hi]])
    z_dom = np.concatenate([[z0_dom], cum_dom[keep], [cum_dom[keep][-1] if keep.any() else z0_dom]])
    z_int = np.concatenate([[z0_int], cum_int[keep], [cum_int[keep][-1] if keep.any() else z0_int]])
    return t, z_dom, z_int


def draw_z_vs_tol(
    packing: Packing, coordination: Coordination, contacts: Contacts | None
) -> Figure:
    """Fig. 14: Z against the contact tolerance, over the whole sweep and a zoom on small tol.

    The zoom spans ``d_min / 100`` to ``d_min / 20`` (0.02 to 0.1 at the built-in
    scenes' ``d_min = 2``; see :func:`regopack.base.units.length_scale`).

    Lines are the exact step curves from the contact thresholds (when the
    contacts analyzer is at hand); markers are the sweep of the coordination
    analyzer, as written to ``analysis.json``.
    """
    fig = Figure(figsize=(WIDTH, 2.9))
    axes = fig.subplots(1, 2)
    tols = coordination.tols
    unit = length_unit(packing)
    scale = length_scale(packing)
    zoom_lo, zoom_hi = ZOOM_TOL[0] * scale, ZOOM_TOL[1] * scale
    lo_full = float(min(tols.min(), zoom_lo))
    hi_full = float(tols.max())
    if contacts is not None:
        hi_full = max(hi_full, contacts.tol_max)
    tol = coordination.results()["tol"]
    ranges = (
        (lo_full, hi_full, "full range"),
        (zoom_lo, zoom_hi, f"zoom on {zoom_lo:g}–{zoom_hi:g} {unit}"),
    )
    series = (
        ("domain", "#0072B2", "o", coordination.z_tol_domain),
        ("interior", "#D55E00", "s", coordination.z_tol_interior),
    )
    for ax, (lo, hi, title) in zip(axes, ranges, strict=True):
        curves: tuple[FloatArray, ...] = ()
        if contacts is not None:
            t, z_dom, z_int = _exact_z_of_tol(packing, contacts, lo, hi)
            curves = (z_dom, z_int)
        sel = (tols >= lo) & (tols <= hi)
        for k, (label, colour, marker, z_sweep) in enumerate(series):
            if curves:
                ax.step(t, curves[k], where="post", color=colour, label=label)
            ax.plot(
                tols[sel],
                z_sweep[sel],
                marker,
                color=colour,
                mfc="white",
                clip_on=False,
                zorder=3,
                label=None if curves else label,
            )
        ax.axvline(
            tol, color="#555555", linestyle=":", linewidth=0.8, label=f"tol = {tol:g} {unit}"
        )
        ax.set_xlim(lo, hi)
        # small tolerances (a packing in mm or m) as multiples of a power of ten
        ax.ticklabel_format(axis="x", style="sci", scilimits=(-3, 4))
        ax.set_xlabel(f"contact tolerance tol ({unit})")
        ax.set_ylabel("coordination number Z")
        ax.set_title(title)
    handles, labels = axes[0].get_legend_handles_labels()
    if curves:
        handles.append(Line2D([], [], linestyle="none", marker="o", color="#555555", mfc="white"))
        labels.append("sweep (analysis.json)")
    axes[1].legend(handles, labels, loc="lower right")
    return fig


def draw_z_per_mineral(packing: Packing, coordination: Coordination) -> Figure:
    """Fig. 15: distribution of the contact count per mineral, and its mean (interior particles)."""
    names = packing.mineral_names
    colours = mineral_colours(names)
    fig = Figure(figsize=(WIDTH, 2.9))
    ax, bar_ax = fig.subplots(1, 2, width_ratios=(2.2, 1))
    z = coordination.per_particle
    interior = coordination.interior
    z_in = z[interior]
    top = int(np.percentile(z_in, 99.5)) if z_in.size else 0
    ks = np.arange(0, max(top, 1) + 1)
    means, errs = [], []
    # Z is an integer: one bar per mineral at each Z, side by side
    bar = Z_BARS_WIDTH / max(len(names), 1)
    for m, (name, colour) in enumerate(zip(names, colours, strict=True)):
        zm = z[interior & (packing.mineral == m)]
        if zm.size == 0:
            means.append(np.nan)
            errs.append(0.0)
            continue
        p = np.bincount(np.minimum(zm, ks[-1]), minlength=len(ks))[: len(ks)] / zm.size
        ax.bar(
            ks + (m - 0.5 * (len(names) - 1)) * bar,
            p,
            width=bar,
            color=colour,
            label=f"{name} (n = {zm.size:,})",
            edgecolor="#333333",
            linewidth=0.3,
        )
        means.append(float(zm.mean()))
        errs.append(float(zm.std(ddof=1) / np.sqrt(zm.size)) if zm.size > 1 else 0.0)
    ax.set_xlim(ks[0] - 0.5, ks[-1] + 0.5)
    ax.set_xlabel(f"contacts per particle Z (last bars: Z ≥ {ks[-1]})")
    ax.xaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_ylabel("fraction of the mineral's particles")
    if z_in.size:  # no interior particle: no bar, no legend
        ax.legend(loc="upper right")
    tol = coordination.results()["tol"]
    ax.set_title(f"distribution of Z, interior particles, tol = {tol:g} {length_unit(packing)}")
    x = np.arange(len(names))
    bar_ax.bar(
        x,
        means,
        yerr=errs,
        color=colours,
        edgecolor="#333333",
        linewidth=0.4,
        error_kw={"elinewidth": 0.8, "capsize": 2},
    )
    z_all = coordination.results()["z_interior"]
    if z_all is not None:
        bar_ax.axhline(
            z_all, color=TOTAL, linestyle="--", linewidth=0.8, label=f"all minerals: {z_all:.2f}"
        )
        bar_ax.legend(loc="upper right")
    bar_ax.set_xticks(x, names, rotation=45, ha="right")
    bar_ax.set_ylabel("mean Z (± standard error)")
    bar_ax.set_title("mean Z per mineral")
    finite = [v for v in means if np.isfinite(v)]
    if finite and max(finite) > 0:
        bar_ax.set_ylim(0, max(finite) * 1.3)
    return fig


def mineral_centred_rdf(
    curves: Mapping[str, FloatArray], names: Sequence[str], counts: Sequence[int]
) -> dict[str, FloatArray]:
    """g(r) of all centres around the particles of each mineral, from the pair curves.

    With ``N_B`` particles of mineral ``B`` (``N`` in all) and the pair curves
    ``g_AB``, the curve around mineral ``A`` is
    ``(g_AA (N_A - 1) + sum_{B != A} g_AB N_B) / (N - 1)``: the same
    translation-corrected estimator, counting every neighbour of an ``A``
    particle. It is far less noisy than ``g_AA`` for rare minerals.
    """
    total = float(sum(counts))
    out: dict[str, FloatArray] = {}
    if total < 2:
        return out
    for a, name_a in enumerate(names):
        acc = np.zeros_like(curves["r"])
        ok = True
        for b, name_b in enumerate(names):
            key = f"{name_a}-{name_b}" if f"{name_a}-{name_b}" in curves else f"{name_b}-{name_a}"
            if key not in curves:
                ok = False
                break
            weight = counts[b] - 1.0 if a == b else float(counts[b])
            if weight > 0:
                acc = acc + weight * np.nan_to_num(curves[key])
        if ok and counts[a] > 0:
            out[name_a] = acc / (total - 1.0)
    return out


def draw_binned(ax: Axes, curve: BinnedCurve, step: float, **kwargs: Any) -> bool:
    """Draw merged bins as steps over their extent, bins of the fine width ``step`` as a line.

    A curve of a single bin has no shape to show and is not drawn (the
    return value is then false). ``kwargs`` go to
    :meth:`~matplotlib.axes.Axes.stairs` or :meth:`~matplotlib.axes.Axes.plot`.
    """
    if curve.g.size < 2 or not np.isfinite(curve.g).any():
        return False
    if curve.widest > 1.5 * step:
        ax.stairs(curve.g, curve.edges, baseline=None, **kwargs)
    else:
        ax.plot(0.5 * (curve.r_lo + curve.r_hi), curve.g, **kwargs)
    return True


def note_single_bins(ax: Axes, names: Sequence[str]) -> None:
    """Name, in a corner of ``ax``, the curves left out because their bins merged into one."""
    if names:
        ax.text(
            0.99,
            0.98,
            textwrap.fill("too few pairs for a curve: " + ", ".join(names), NOTE_WIDTH),
            transform=ax.transAxes,
            ha="right",
            va="top",
            fontsize=6,
            color="#555555",
        )


def legend_entries(axes: Sequence[Axes], order: Sequence[str]) -> tuple[list[Any], list[str]]:
    """Collect the handles and labels of all ``axes``, each label once, in the given order."""
    entries: dict[str, Any] = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels(), strict=True):
            entries.setdefault(label, handle)
    labels = [label for label in order if label in entries]
    labels += [label for label in entries if label not in labels]
    return [entries[label] for label in labels], labels


def mark_first_peak(ax: Axes, peak: PeakFit | None, unit: str, places: int) -> None:
    """Mark the first peak with its ± 1 σ band, or the plateau when the top is no distinct peak."""
    if peak is None:
        return
    if peak.distinct:
        ax.axvspan(peak.r - peak.r_err, peak.r + peak.r_err, color="#bbbbbb", alpha=0.5, lw=0)
        ax.axvline(peak.r, color=TOTAL, linestyle="--", linewidth=0.7)
        x = peak.r
        text = f" first peak {peak.r:.{places}f} ± {peak.r_err:.{places}f} {unit}"
    else:
        ax.axvspan(peak.r_lo, peak.r_hi, color="#dddddd", alpha=0.7, lw=0)
        x = peak.r_lo
        text = (
            f" no distinct first peak: plateau {peak.r_lo:.{places}f}–{peak.r_hi:.{places}f} {unit}"
        )
    ax.text(x, 0.04, text, transform=ax.get_xaxis_transform(), fontsize=6.5)


def _mineral_centred_curves(
    ax: Axes, packing: Packing, rdf: Rdf, key: str, colours: Sequence[str], step: float
) -> list[str]:
    """Draw g(r) around the particles of each mineral (2D); return the minerals left out."""
    from regopack.plugins.analyzers.common import interior_mask

    names = packing.mineral_names
    sel = interior_mask(packing, float(rdf.results()["interior_margin"]))
    counts = np.bincount(packing.mineral[sel], minlength=len(names)).tolist()
    r = rdf.curves[key]["r"]
    edges = rdf.edges[key]
    per = mineral_centred_rdf(rdf.curves_fine[key], names, counts) if len(names) > 1 else {}
    shell = np.pi * (edges[1:] ** 2 - edges[:-1] ** 2)
    n_all = max(float(sum(counts)), 1.0)
    single = []
    for m, (name, colour) in enumerate(zip(names, colours, strict=True)):
        if name in per:
            # bins merged as for the pair curves: N_A (N - 1) pairs around mineral A
            per_bin = 2.0 * counts[m] / n_all * float(rdf.expected[key][len(r) // 2])
            factor = count_bins(per_bin, rdf.config.min_pairs_per_bin, len(r))
            merged = merge_bins(edges, per[name], shell, factor)
            if not draw_binned(ax, merged, step, color=colour, linewidth=0.8, label=name):
                single.append(name)
    return single


def _self_pair_curves(
    ax: Axes, packing: Any, rdf: Rdf, key: str, colours: Sequence[str], step: float
) -> list[str]:
    """Draw g(r) of each mineral with itself (3D); return the curves left out."""
    pairs = rdf.pair_curves.get(key, {})
    single = []
    for name, colour in zip(packing.mineral_names, colours, strict=True):
        curve = pairs.get(f"{name}-{name}")
        label = f"{name}–{name}"
        if curve is not None and not draw_binned(
            ax, curve, step, color=colour, linewidth=0.8, label=label
        ):
            single.append(label)
    return single


def draw_rdf(packing: Any, rdf: Rdf) -> Figure:
    """Fig. 16: g(r) of all centres and of each mineral; near and far field.

    Around the particles of each mineral in 2D, of each mineral with itself in 3D.
    """
    names = packing.mineral_names
    colours = mineral_colours(names)
    unit = length_unit(packing)
    places = decimals(length_scale(packing), 2)
    solid = packing.domain.dimension == 3
    minerals = _self_pair_curves if solid else _mineral_centred_curves
    fig = Figure(figsize=(WIDTH, 3.0))
    axes = fig.subplots(1, 2)
    for ax, key, title in zip(axes, ("near", "far"), ("near field", "far field"), strict=True):
        curves = rdf.curves.get(key)
        if curves is None:
            note(ax, f"no {title} (window too small)")
            continue
        r = curves["r"]
        step = float(r[1] - r[0]) if len(r) > 1 else 0.0
        note_single_bins(ax, minerals(ax, packing, rdf, key, colours, step))
        ax.plot(r, curves["total"], color=TOTAL, linewidth=1.2, label="all particles")
        ax.axhline(1.0, color="#777777", linestyle=":", linewidth=0.7)
        mark_first_peak(ax, rdf.peak if key == "near" else None, unit, places)
        ax.set_xlim(float(r[0]) - 0.5 * step, float(r[-1]) + 0.5 * step)
        ax.set_xlabel(f"centre distance r ({unit})")
        ax.set_ylabel("g(r)")
        ax.set_title(f"{title}, bins of {step:g} {unit}")
    merged = "(a rare mineral's bins merged: steps over the merged bins)"
    if solid:
        res = rdf.results()
        window = " × ".join(f"{s:g}" for s in res["window"])
        labels = [f"{n}–{n}" for n in names]
        title = f"{res['n_points']:,} interior centres; window {window} {unit} {merged}"
    else:
        labels, title = list(names), f"centres around the particles of {merged}"
    handles, order = legend_entries(axes, [*labels, "all particles"])
    if handles:
        fig.legend(
            handles,
            order,
            loc="outside lower center",
            ncol=min(len(handles), 4 if solid else 7),
            title=title,
            title_fontsize=7,
        )
    return fig


# ---------------------------------------------------------------------------

_A = TypeVar("_A", bound=Analyzer)


def _computed(analyzers: Mapping[str, Analyzer], kind: type[_A]) -> _A | None:
    """Return the computed analyzer of type ``kind``, under whichever name it was filed."""
    return next((a for a in analyzers.values() if isinstance(a, kind)), None)


def figures_for(
    packing: Any,
    analyzers: Mapping[str, Analyzer],
    out_dir: str | Path,
    *,
    formats: Sequence[str] = ("png", "svg"),
    stems: Collection[str] | None = None,
) -> list[Path]:
    """Draw the figures whose analyzers were computed; return the files written.

    Parameters
    ----------
    packing
        The analysed packing, 2D or 3D.
    analyzers
        Computed analyzers by name (as :func:`regopack.analysis.pipeline.run_analyses`
        returns them, under new or old names). Figures are drawn for ``density``
        (the packing), ``network``, ``contacts``, ``coordination``, ``rdf``,
        ``homogeneity``, ``psd`` and ``local_fraction``; other analyzers are
        ignored. A 3D packing has no packing and network figures.
    out_dir
        Directory of the figures (created if needed).
    formats
        File formats to write, among those matplotlib supports (``"pdf"`` too).
    stems
        Draw only the figures of these file stems (see
        :data:`~regopack.plugins.analyzers.figure_specs.STEMS`); by default all.

    Returns
    -------
    list of Path
        ``<stem>.<format>`` of every figure drawn, figure by figure.
    """
    out = Path(out_dir)
    solid = packing.domain.dimension == 3
    end = "-3d" if solid else ""
    contacts = _computed(analyzers, Contacts)
    coordination = _computed(analyzers, Coordination)
    rdf = _computed(analyzers, Rdf)
    jobs: list[tuple[str, Callable[[], Figure]]] = []
    if not solid and _computed(analyzers, Density) is not None:
        jobs.append(("packing", lambda: draw_packing(packing)))
    if not solid and _computed(analyzers, Network) is not None and contacts is not None:
        jobs.append(("contact-network", lambda: draw_network(packing, contacts)))
    if contacts is not None:
        jobs.append((f"contact-histograms{end}", lambda: draw_contact_histograms(contacts)))
    if coordination is not None:
        jobs.append((f"z-vs-tol{end}", lambda: draw_z_vs_tol(packing, coordination, contacts)))
        jobs.append((f"z-per-mineral{end}", lambda: draw_z_per_mineral(packing, coordination)))
    if rdf is not None:
        jobs.append((f"rdf{end}", lambda: draw_rdf(packing, rdf)))
    homogeneity = _computed(analyzers, Homogeneity)
    if homogeneity is not None:
        from regopack.plugins.analyzers.homogeneity_figure import draw_homogeneity

        jobs.append((f"homogeneity{end}", lambda: draw_homogeneity(packing, homogeneity)))
    psd = _computed(analyzers, Psd)
    if psd is not None:
        from regopack.plugins.analyzers.psd_figure import draw_psd

        jobs.append((f"psd{end}", lambda: draw_psd(psd, length_unit(packing))))
    local_fraction = _computed(analyzers, LocalFraction)
    if local_fraction is not None and not solid:
        from regopack.plugins.analyzers.local_fraction_figure import draw_local_fraction

        lf = local_fraction
        jobs.append(("local-fraction", lambda: draw_local_fraction(packing, lf)))
    if stems is not None:
        jobs = [(stem, draw) for stem, draw in jobs if stem in stems]
    if not jobs:
        return []
    out.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    with style():
        for stem, draw in jobs:
            paths += save(draw(), out, stem, formats)
    return paths

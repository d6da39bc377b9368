"""Figures of the structure analysis, drawn with matplotlib off screen.

:func:`figures_for` draws the figures whose analyzers were computed and saves
each as PNG (300 dpi) and SVG:

========================  ======================  ==========================================
file stem                 needs                   shows (figure of the paper)
========================  ======================  ==========================================
``packing``               ``density``             particles coloured by mineral, zoom (10)
``contact-network``       ``network``             centre-to-centre edges, width ∝ A_c (12)
``contact-histograms``    ``contacts``            A_c, b_c, R_c, δ on log axes (13)
``z-vs-tol``              ``coordination``        Z against tol, full range and zoom (14)
``z-per-mineral``         ``coordination``        distribution of Z per mineral (15)
``rdf``                   ``rdf``                 g(r) per mineral, near and far field (16)
``homogeneity``           ``homogeneity``         ring profiles with trends, tile maps
``psd``                   ``psd``                 percent passing, class shares
``local-fraction``        ``local_fraction``      map of local φ per particle, histogram
========================  ======================  ==========================================

Figures are sized for a journal page (7 in wide, 8 pt text) and colour the
minerals by name from one colour-blind-safe palette (Okabe and Ito; see
:mod:`regopack.base.colours`), so a mineral keeps its colour in every scene.
Lengths are labelled in the scene's ``length_unit`` (micrometres by default).
Collections with many items are rasterised inside the SVG files to keep them
small; axes and text stay vector.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any, cast

import matplotlib
import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import ConnectionPatch, Patch, Rectangle
from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator, NullFormatter
from numpy.typing import NDArray

from regopack.base.colours import PALETTE, mineral_colours
from regopack.base.units import decimals, length_scale, length_unit
from regopack.packing.core import Packing, _atomic_file
from regopack.plugins.analyzers.contacts import Contacts
from regopack.plugins.analyzers.coordination import Coordination
from regopack.plugins.analyzers.figure_specs import CAPTIONS, STEMS
from regopack.plugins.analyzers.homogeneity import Homogeneity
from regopack.plugins.analyzers.local_fraction import LocalFraction
from regopack.plugins.analyzers.psd import Psd
from regopack.plugins.analyzers.rdf import Rdf
from regopack.plugins.analyzers.rdf_peak import BinnedCurve, PeakFit, count_bins, merge_bins
from regopack.registry.interfaces import Analyzer

__all__ = [
    "CAPTIONS",
    "PALETTE",
    "draw_binned",
    "figures_for",
    "legend_entries",
    "mark_first_peak",
    "mineral_colours",
]

FloatArray = NDArray[np.float64]


WIDTH = 7.0
"""Width of the figures in inches (a two-column journal page)."""

DPI = 300
"""Resolution of the PNG files."""

MAX_LINE_PT = 2.5
"""Line width, in points, of the contact with the largest A_c in the network figure."""

RASTERISE_ABOVE = 2000
"""Collections with more items than this are rasterised inside the SVG files."""

ZOOM_TOL = (0.02, 0.1)
"""Range of tol of the zoom of ``z-vs-tol`` at the built-in scale (``d_min = 2``): ``d_min / 100``
to ``d_min / 20``, times :func:`~regopack.base.units.length_scale` for other packings."""

_STYLE: dict[str, Any] = {
    "font.size": 8,
    "axes.titlesize": 8,
    "axes.labelsize": 8,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "legend.fontsize": 7,
    "legend.frameon": False,
    "axes.linewidth": 0.6,
    "xtick.major.width": 0.6,
    "ytick.major.width": 0.6,
    "xtick.minor.width": 0.4,
    "ytick.minor.width": 0.4,
    "lines.linewidth": 1.0,
    "lines.markersize": 3.5,
    "svg.fonttype": "none",
    "svg.hashsalt": "regopack",
    "figure.constrained_layout.use": True,
}

_AC = r"$A_\mathrm{c}$"

TOTAL = "#000000"
"""Colour of whole-packing curves (all minerals together)."""

NOTE_WIDTH = 36
"""Characters per line of the notes written inside a panel."""

Z_BARS_WIDTH = 0.8
"""Width, in units of Z, of the group of bars (one per mineral) at each value of Z."""


# ---------------------------------------------------------------------------
# helpers


@contextmanager
def _style() -> Iterator[None]:
    with matplotlib.rc_context(cast(Any, _STYLE)):
        yield


def _save(fig: Figure, out_dir: Path, stem: str, formats: Sequence[str]) -> list[Path]:
    """Write ``fig`` as ``stem.<format>`` for every format, each atomically."""
    paths = []
    for fmt in formats:
        path = out_dir / f"{stem}.{fmt}"
        metadata = {"Date": None} if fmt == "svg" else {}
        with _atomic_file(path) as fh:
            fig.savefig(fh, format=fmt, dpi=DPI, metadata=metadata)
        paths.append(path)
    return paths


def _polygons(
    packing: Packing, idx: NDArray[np.int64], colours: Sequence[str], **kwargs: Any
) -> PolyCollection:
    faces = np.asarray(colours, dtype=object)[packing.mineral[idx]]
    coll = PolyCollection(packing.polygons(idx), closed=True, facecolors=list(faces), **kwargs)
    coll.set_rasterized(len(idx) > RASTERISE_ABOVE)
    return coll


DENSITY_DECADES = 3
"""A number density is drawn in 10⁻³ length unit⁻² at the built-in scale."""

_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def axis_unit(power: int, unit: str, scale: float) -> tuple[str, float]:
    """Return the axis unit of a quantity of length dimension ``power``, and its factor.

    The values are drawn in decades of ``unit`` chosen so that they read as at
    the built-in scale (``scale``, :func:`~regopack.base.units.length_scale`, is 1):
    a packing in millimetres draws its coordinates and mean diameter in
    10⁻³ mm and its number density in 10³ mm⁻², the same numbers as µm and
    10⁻³ µm⁻².

    Examples
    --------
    >>> axis_unit(-2, "µm", 1.0), axis_unit(-2, "mm", 1e-3), axis_unit(1, "mm", 1e-3)
    (('10⁻³ µm⁻²', 1000.0), ('10³ mm⁻²', 0.001), ('10⁻³ mm', 1000.0))
    >>> axis_unit(1, "µm", 1.0), axis_unit(0, "µm", 1.0)
    (('µm', 1.0), ('', 1.0))
    """
    if power == 0:
        return "", 1.0
    decade = round(-math.log10(scale)) if math.isfinite(scale) and scale > 0 else 0
    exponent = decade * power + (DENSITY_DECADES if power == -2 else 0)
    text = unit if power == 1 else f"{unit}{str(power).translate(_SUPERSCRIPT)}"
    if exponent == 0:
        return text, 1.0
    return f"10{str(-exponent).translate(_SUPERSCRIPT)} {text}", float(10.0**exponent)


def length_ticks(ax: Axes, unit: str, scale: float) -> str:
    """Write the x and y ticks of a map in the decade of ``unit`` of :func:`axis_unit`.

    Returns the unit text of the axis labels (``unit`` itself at the built-in
    scale, where the ticks are left as matplotlib writes them).
    """
    text, factor = axis_unit(1, unit, scale)
    if factor != 1.0:
        ticks = FuncFormatter(lambda v, _: f"{v * factor:.6g}".replace("-", "\N{MINUS SIGN}"))
        ax.xaxis.set_major_formatter(ticks)
        ax.yaxis.set_major_formatter(ticks)
    return text


def _frame(ax: Axes, bounds: Sequence[float], unit: str = "µm", scale: float = 1.0) -> None:
    """Set the limits, equal aspect and labels of a map of the packing.

    Lengths are in ``unit`` at the ``scale`` of the packing (:func:`axis_unit`:
    coordinates of a packing in mm are labelled in 10⁻³ mm).
    """
    xmin, xmax, ymin, ymax = (float(b) for b in bounds)
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal")
    text = length_ticks(ax, unit, scale)
    ax.set_xlabel(f"x ({text})")
    ax.set_ylabel(f"y ({text})")


NICE_STEPS = (1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0)
"""Mantissas of the round lengths that zoom windows take."""


def nice_length(length: float, most: float | None = None) -> float:
    """Round ``length`` to the nearest (in ratio) of 1, 1.2, 1.5, 2, 2.5, 3, 4, 5, 6, 8 × 10^k.

    With ``most``, the result is the largest such length not above ``most``
    when the nearest one is (and ``most`` itself when no round length is).

    Examples
    --------
    >>> nice_length(128.447), nice_length(100.0), nice_length(0.0173)
    (120.0, 100.0, 0.015)
    >>> nice_length(128.447, most=110.0)
    100.0
    """
    if not (length > 0 and np.isfinite(length)):
        return length
    exponent = 10.0 ** np.floor(np.log10(length))
    candidates = [float(f"{m * exponent * s:.6g}") for s in (0.1, 1.0) for m in NICE_STEPS]
    if most is not None:
        below = [c for c in candidates if c <= most]
        if not below:
            return most
        if min(candidates, key=lambda c: abs(np.log(c / length))) > most:
            return max(below)
        candidates = below
    return min(candidates, key=lambda c: abs(np.log(c / length)))


def length_text(value: float) -> str:
    """Format a length for a title: three significant digits, no exponent below 10^6.

    Examples
    --------
    >>> length_text(128.447), length_text(1600.0), length_text(0.012345)
    ('128', '1600', '0.0123')
    """
    return f"{float(f'{value:.3g}'):g}"


def _zoom_window(packing: Packing) -> tuple[float, float, float, float]:
    """Square window at the domain's centre: an eighth of its size, at least 20 mean radii.

    The side is rounded to a round length (:func:`nice_length`), at most the
    domain's shorter side.
    """
    dom = packing.domain
    short = min(dom.width, dom.height)
    placed = packing.placed
    mean_r = float(packing.radius[placed].mean()) if placed.any() else short / 40
    side = nice_length(min(short, max(short / 8, 20.0 * mean_r)), most=short)
    cx, cy = dom.center
    return cx - side / 2, cx + side / 2, cy - side / 2, cy + side / 2


def _zoom_size(window: Sequence[float], unit: str = "µm") -> str:
    """``"120 × 120 µm"`` for a window ``(x0, x1, y0, y1)`` (lengths in ``unit``)."""
    x0, x1, y0, y1 = window
    return f"{length_text(x1 - x0)} × {length_text(y1 - y0)} {unit}"


def _in_window(packing: Packing, window: Sequence[float]) -> NDArray[np.int64]:
    """Placed particles that may reach into ``window``."""
    x0, x1, y0, y1 = window
    idx = np.flatnonzero(packing.placed)
    c = packing.centre[idx]
    r = packing.circumradius[idx]
    near = (c[:, 0] + r > x0) & (c[:, 0] - r < x1) & (c[:, 1] + r > y0) & (c[:, 1] - r < y1)
    return idx[near].astype(np.int64)


def _link_zoom(fig: Figure, ax: Axes, zoom: Axes, window: Sequence[float], colour: str) -> None:
    """Outline ``window`` on ``ax`` and join its right corners to the left side of ``zoom``."""
    x0, x1, y0, y1 = window
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, edgecolor=colour, linewidth=0.9))
    for y_data, y_axes in ((y1, 1.0), (y0, 0.0)):
        fig.add_artist(
            ConnectionPatch(
                xyA=(x1, y_data),
                coordsA=ax.transData,
                xyB=(0.0, y_axes),
                coordsB=zoom.transAxes,
                color=colour,
                linewidth=0.7,
            )
        )


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


def _note(ax: Axes, text: str) -> None:
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", color="#555555")


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
    _frame(ax, dom.bounds().tolist(), unit, length_scale(packing))
    ax.set_title(_title(packing))
    window = _zoom_window(packing)
    near = _in_window(packing, window)
    zoom.add_collection(_polygons(packing, near, colours, edgecolors="#222222", linewidths=0.3))
    _frame(zoom, window, unit, length_scale(packing))
    zoom.set_title(f"zoom: {_zoom_size(window, unit)} at the centre")
    _link_zoom(fig, ax, zoom, window, "black")
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
    window = _zoom_window(packing)
    x0, x1, y0, y1 = window
    mid = 0.5 * (segments[:, 0] + segments[:, 1])
    inside = (mid[:, 0] > x0) & (mid[:, 0] < x1) & (mid[:, 1] > y0) & (mid[:, 1] < y1)
    near = _in_window(packing, window)
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
    _frame(ax, dom.bounds().tolist(), unit, length_scale(packing))
    _frame(zoom, window, unit, length_scale(packing))
    ax.set_title(f"{len(area):,} contacts at tol = {contacts.tol:g} {unit}")
    widths_note = f" (widths × {factor:.2g})" if factor > 1.05 else ""
    zoom.set_title(f"zoom, {_zoom_size(window, unit)} at the centre{widths_note}")
    _link_zoom(fig, ax, zoom, window, "#D55E00")
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
        _note(ax, "no contacts")
    return fig


def _log_hist(ax: Axes, values: FloatArray, label: str, unit: str, colour: str = "#0072B2") -> None:
    v = values[np.isfinite(values) & (values > 0)]
    if v.size == 0:
        _note(ax, "no contacts")
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
    """Fig. 13: histograms of A_c, b_c, R_c and δ with log-spaced bins on log axes."""
    fig = Figure(figsize=(WIDTH, 4.6))
    axes = fig.subplots(2, 2)
    tol = contacts.tol
    u = length_unit(contacts.packing)
    panels = (
        (contacts.area, f"contact area {_AC} ({u}²)", f"{u}²"),
        (contacts.width, rf"contact width $b_\mathrm{{c}}$ ({u})", u),
        (contacts.radius, rf"segment radius $R_\mathrm{{c}}$ ({u})", u),
        (contacts.depth, rf"segment depth $\delta$ ({u})", u),
    )
    for ax, (values, label, unit) in zip(axes.ravel(), panels, strict=True):
        _log_hist(ax, values, label, unit)
    ax_d = axes[1, 1]
    if contacts.depth.size:
        ax_d.axvline(tol, color="#D55E00", linewidth=0.9, label=f"tol = {tol:g} {u}")
        ax_d.axvline(
            1.5 * tol, color="#D55E00", linestyle=":", linewidth=0.9, label="1.5 tol (face to face)"
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


def draw_rdf(packing: Packing, rdf: Rdf) -> Figure:
    """Fig. 16: g(r) of all centres, and around the particles of each mineral; near and far."""
    from regopack.plugins.analyzers.common import interior_mask

    names = packing.mineral_names
    colours = mineral_colours(names)
    unit = length_unit(packing)
    places = decimals(length_scale(packing), 2)
    res = rdf.results()
    sel = interior_mask(packing, float(res["interior_margin"]))
    counts = np.bincount(packing.mineral[sel], minlength=len(names)).tolist()
    fig = Figure(figsize=(WIDTH, 3.0))
    axes = fig.subplots(1, 2)
    for ax, key, title in zip(axes, ("near", "far"), ("near field", "far field"), strict=True):
        curves = rdf.curves.get(key)
        if curves is None:
            _note(ax, f"no {title} (window too small)")
            continue
        r = curves["r"]
        step = float(r[1] - r[0]) if len(r) > 1 else 0.0
        edges = rdf.edges[key]
        fine = rdf.curves_fine[key]
        per = mineral_centred_rdf(fine, names, counts) if len(names) > 1 else {}
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
        note_single_bins(ax, single)
        ax.plot(r, curves["total"], color=TOTAL, linewidth=1.2, label="all particles")
        ax.axhline(1.0, color="#777777", linestyle=":", linewidth=0.7)
        mark_first_peak(ax, rdf.peak if key == "near" else None, unit, places)
        ax.set_xlim(float(r[0]) - 0.5 * step, float(r[-1]) + 0.5 * step)
        ax.set_xlabel(f"centre distance r ({unit})")
        ax.set_ylabel("g(r)")
        ax.set_title(f"{title}, bins of {step:g} {unit}")
    handles, labels = legend_entries(axes, [*names, "all particles"])
    if handles:
        fig.legend(
            handles,
            labels,
            loc="outside lower center",
            ncol=min(len(handles), 7),
            title="centres around the particles of (a rare mineral's bins merged: steps over "
            "the merged bins)",
            title_fontsize=7,
        )
    return fig


# ---------------------------------------------------------------------------


def figures_for(
    packing: Packing,
    analyzers: Mapping[str, Analyzer],
    out_dir: str | Path,
    *,
    formats: Sequence[str] = ("png", "svg"),
    of: str | None = None,
) -> list[Path]:
    """Draw the figures whose analyzers were computed; return the files written.

    Parameters
    ----------
    packing
        The analysed packing.
    analyzers
        Computed analyzers by name (as :func:`regopack.analysis.pipeline.run_analyses`
        returns them). Figures are drawn for ``density`` (the packing),
        ``network``, ``contacts``, ``coordination``, ``rdf``, ``homogeneity``
        ``psd`` and ``local_fraction``; other analyzers are ignored.
    out_dir
        Directory of the figures (created if needed).
    formats
        File formats to write, among those matplotlib supports (``"pdf"`` too).
    of
        Draw only the figures of this analyzer (see
        :data:`~regopack.plugins.analyzers.figure_specs.STEMS`); by default all.

    Returns
    -------
    list of Path
        ``<stem>.<format>`` of every figure drawn, figure by figure.
    """
    out = Path(out_dir)
    contacts = analyzers.get("contacts")
    contacts = contacts if isinstance(contacts, Contacts) else None
    coordination = analyzers.get("coordination")
    rdf = analyzers.get("rdf")
    jobs: list[tuple[str, Callable[[], Figure]]] = []
    if "density" in analyzers:
        jobs.append(("packing", lambda: draw_packing(packing)))
    if "network" in analyzers and contacts is not None:
        jobs.append(("contact-network", lambda: draw_network(packing, contacts)))
    if contacts is not None:
        jobs.append(("contact-histograms", lambda: draw_contact_histograms(contacts)))
    if isinstance(coordination, Coordination):
        jobs.append(("z-vs-tol", lambda: draw_z_vs_tol(packing, coordination, contacts)))
        jobs.append(("z-per-mineral", lambda: draw_z_per_mineral(packing, coordination)))
    if isinstance(rdf, Rdf):
        jobs.append(("rdf", lambda: draw_rdf(packing, rdf)))
    homogeneity = analyzers.get("homogeneity")
    if isinstance(homogeneity, Homogeneity):
        from regopack.plugins.analyzers.homogeneity_figure import draw_homogeneity

        jobs.append(("homogeneity", lambda: draw_homogeneity(packing, homogeneity)))
    psd = analyzers.get("psd")
    if isinstance(psd, Psd):
        from regopack.plugins.analyzers.psd_figure import draw_psd

        jobs.append(("psd", lambda: draw_psd(psd, length_unit(packing))))
    local_fraction = analyzers.get("local_fraction")
    if isinstance(local_fraction, LocalFraction):
        from regopack.plugins.analyzers.local_fraction_figure import draw_local_fraction

        lf = local_fraction
        jobs.append(("local-fraction", lambda: draw_local_fraction(packing, lf)))
    if of is not None:
        jobs = [(stem, draw) for stem, draw in jobs if stem in STEMS.get(of, ())]
    if not jobs:
        return []
    out.mkdir(parents=True, exist_ok=True)
    paths: list[Path] = []
    with _style():
        for stem, draw in jobs:
            paths += _save(draw(), out, stem, formats)
    return paths

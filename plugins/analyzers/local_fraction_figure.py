"""Figure of the local packing fraction: particle map, zoom with the cells, histogram."""

from __future__ import annotations

import matplotlib
import matplotlib.colors as mcolors
import numpy as np
import shapely
from matplotlib.axes import Axes
from matplotlib.cm import ScalarMappable
from matplotlib.collections import PolyCollection
from matplotlib.figure import Figure
from numpy.typing import NDArray

from regopack.base.units import length_scale, length_unit
from regopack.packing.core import Packing
from regopack.plugins.analyzers.figure_style import (
    RASTERISE_ABOVE,
    WIDTH,
    frame,
    in_window,
    link_zoom,
    note,
    zoom_size,
    zoom_window,
)
from regopack.plugins.analyzers.local_fraction import LocalFraction

__all__ = ["draw_local_fraction"]

CMAP = "viridis"
MISSING = "#bbbbbb"
"""Face colour of a particle without a value (an empty cell)."""
DOMAIN = "#0072B2"
INTERIOR = "#D55E00"
LABEL = {"laguerre": "Laguerre", "voronoi": "Voronoi"}


def _norm(phi: NDArray[np.float64]) -> mcolors.Normalize:
    """Colour scale over the 1st to 99th percentile of the values, rounded to 0.05."""
    finite = phi[np.isfinite(phi)]
    if finite.size == 0:
        return mcolors.Normalize(0.0, 1.0)
    lo, hi = np.percentile(finite, [1.0, 99.0])
    lo, hi = np.floor(lo * 20.0) / 20.0, np.ceil(hi * 20.0) / 20.0
    return mcolors.Normalize(float(lo), float(max(hi, lo + 0.05)))


def _particles(
    ax: Axes, packing: Packing, idx: NDArray[np.int64], phi: NDArray[np.float64], **kw: object
) -> PolyCollection:
    coll = PolyCollection(packing.polygons(idx), closed=True, **kw)  # type: ignore[arg-type]
    coll.set_rasterized(len(idx) > RASTERISE_ABOVE)
    ax.add_collection(coll)
    return coll


def _colour(coll: PolyCollection, values: NDArray[np.float64], norm: mcolors.Normalize) -> None:
    cmap = matplotlib.colormaps[CMAP].with_extremes(bad=MISSING)
    coll.set_array(np.ma.masked_invalid(values))
    coll.set_cmap(cmap)
    coll.set_norm(norm)


def _histogram(ax: Axes, lf: LocalFraction) -> None:
    res = lf.results()
    edges = lf.edges
    width = np.diff(edges)
    for counts, colour, label in (
        (lf.hist_domain, DOMAIN, f"all ({res['n_cells']:,})"),
        (lf.hist_interior, INTERIOR, f"interior ({res['n_interior']:,})"),
    ):
        total = counts.sum()
        dens = counts / (total * width) if total else np.zeros_like(width)
        ax.stairs(dens, edges, color=colour, linewidth=1.0, label=label)
    if res["phi_mean_interior"] is not None:
        ax.axvline(res["phi_mean_interior"], color=INTERIOR, linestyle="--", linewidth=0.8)
    if res["phi_cells"] is not None:
        ax.axvline(res["phi_cells"], color="black", linestyle=":", linewidth=0.9)
    handles, labels = ax.get_legend_handles_labels()
    from matplotlib.lines import Line2D

    handles += [
        Line2D([], [], color=INTERIOR, linestyle="--", linewidth=0.8),
        Line2D([], [], color="black", linestyle=":", linewidth=0.9),
    ]
    labels += ["mean φᵢ, interior", "φ, domain"]
    ax.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2)
    ax.set_xlabel("local packing fraction φᵢ")
    ax.set_ylabel("probability density")
    ax.set_xlim(float(edges[0]), float(edges[-1]))
    ax.set_ylim(bottom=0.0)
    ax.set_box_aspect(1.0)


def draw_local_fraction(packing: Packing, lf: LocalFraction) -> Figure:
    """Particles coloured by φᵢ, a zoom on the centre with the cells, and the histogram of φᵢ."""
    res = lf.results()
    unit = length_unit(packing)
    fig = Figure(figsize=(WIDTH, 3.3))
    ax, zoom, hist = fig.subplots(1, 3)
    idx = lf.idx
    phi = lf.phi_local[idx]
    norm = _norm(phi)
    kind = LABEL[res["cells"]]
    if len(idx) == 0:
        note(ax, "no placed particles")
    else:
        _colour(_particles(ax, packing, idx, phi, linewidths=0.0), phi, norm)
    frame(ax, packing.domain.bounds().tolist(), unit, length_scale(packing))
    ax.set_title(f"{packing.n_placed:,} particles, {kind} cells")
    window = zoom_window(packing)
    near = in_window(packing, window)
    coll = _particles(zoom, packing, near, lf.phi_local[near], edgecolors="none")
    _colour(coll, lf.phi_local[near], norm)
    pos = np.searchsorted(idx, near)
    cells = lf.cells[pos]
    rings = [np.asarray(shapely.get_coordinates(c)) for c in cells if not c.is_empty]
    edges = PolyCollection(rings, closed=True, facecolors="none", edgecolors="white")
    edges.set_linewidth(0.5)
    zoom.add_collection(edges)
    frame(zoom, window, unit, length_scale(packing))
    zoom.set_title(f"zoom {zoom_size(window, unit)}; cells white")
    link_zoom(fig, ax, zoom, window, "black")
    _histogram(hist, lf)
    hist.set_title(f"σ(φᵢ) = {res['phi_std_interior'] or float('nan'):.3f} (interior)")
    bar = fig.colorbar(
        ScalarMappable(norm=norm, cmap=CMAP),
        ax=[ax, zoom],
        location="bottom",
        shrink=0.6,
        aspect=30,
        extend="both",
    )
    bar.set_label(f"local packing fraction φᵢ = solid area / area of the {kind} cell")
    return fig

"""Drawing a packing with matplotlib: :meth:`regopack.Packing.plot` and the notebook pictures."""

from __future__ import annotations

import io
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from regopack.base.colours import mineral_colours
from regopack.base.errors import ConfigError
from regopack.base.units import length_unit

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.collections import PolyCollection
    from matplotlib.colorbar import Colorbar
    from matplotlib.legend import Legend
    from matplotlib.lines import Line2D

    from regopack.packing.core import Packing

__all__ = ["COLOR_BY", "PackingArtists", "draw_packing", "packing_png", "summary_line"]

COLOR_BY: dict[str, str] = {
    "mineral": "mineral of each particle (fixed colour per mineral name)",
    "diameter": "equivalent diameter 2r (in the packing's length unit)",
    "radius": "equivalent radius r (in the packing's length unit)",
    "order": "insertion order (0 = placed first)",
    "Z": "contacts per particle at the coordination analyzer's default tolerance",
}
"""Names :func:`draw_packing` takes for ``color_by`` (or pass one value per particle)."""

RASTERISE_ABOVE = 2000
"""Collections with more particles than this are rasterised in vector output."""


@dataclass(frozen=True)
class PackingArtists:
    """What :meth:`regopack.Packing.plot` drew.

    Attributes
    ----------
    ax
        The axes drawn into.
    particles
        One polygon per placed particle, in draw order, followed in a
        periodic domain by the images of those that reach past a side.
    boundary
        The domain's outline.
    legend
        The mineral legend (``color_by="mineral"``), else ``None``.
    colorbar
        The colour bar of a numeric ``color_by``, else ``None``.
    """

    ax: Axes
    particles: PolyCollection
    boundary: Line2D
    legend: Legend | None = None
    colorbar: Colorbar | None = None


def _escape(text: str) -> str:
    """Text that matplotlib shows as it is (a ``$`` would start mathematics)."""
    return text.replace("$", r"\$")


def _wrapped_images(
    packing: Packing, placed: NDArray[np.int64]
) -> tuple[list[NDArray[np.float64]], NDArray[np.int64]]:
    """Outlines of the placed particles and, in a periodic domain, of their images.

    A particle that reaches past a side is drawn again one period away, so
    that the axes, which clip at the sides, show the whole periodic packing.
    Returns the outlines and, for each, the particle it belongs to.
    """
    polygons = packing.polygons(placed)
    owner = placed.copy()
    dom: Any = packing.domain
    if not getattr(dom, "periodic", False) or len(placed) == 0:
        return polygons, owner
    lx, ly = dom.period
    xmin, xmax, ymin, ymax = (float(b) for b in dom.bounds())
    extra: list[NDArray[np.float64]] = []
    extra_owner: list[int] = []
    for k, poly in enumerate(polygons):
        lo, hi = poly.min(axis=0), poly.max(axis=0)
        sx = [0.0] + ([lx] if lo[0] < xmin else []) + ([-lx] if hi[0] > xmax else [])
        sy = [0.0] + ([ly] if lo[1] < ymin else []) + ([-ly] if hi[1] > ymax else [])
        for dx in sx:
            for dy in sy:
                if dx or dy:
                    extra.append(poly + np.array([dx, dy]))
                    extra_owner.append(int(placed[k]))
    return polygons + extra, np.concatenate([owner, np.asarray(extra_owner, dtype=np.int64)])


def _values(packing: Packing, color_by: str | ArrayLike, placed: NDArray[np.int64]) -> Any:
    """Return ``(label, per placed particle values)`` of a numeric ``color_by``."""
    if isinstance(color_by, str):
        if color_by == "diameter":
            return f"equivalent diameter ({length_unit(packing)})", 2.0 * packing.radius[placed]
        if color_by == "radius":
            return f"equivalent radius ({length_unit(packing)})", packing.radius[placed]
        if color_by == "order":
            return "insertion order", packing.insertion_index[placed].astype(np.float64)
        if color_by == "Z":
            from regopack.registry.manager import default_registry
            from regopack.scenes.analysis_plan import run_analyses

            done = run_analyses(packing, default_registry(), [("coordination", {})])
            z = np.asarray(done["coordination"].per_particle)  # type: ignore[attr-defined]
            tol = done["contacts"].results().get("tol")
            label = f"contacts per particle Z (tol = {tol:g} {length_unit(packing)})"
            return label, z[placed].astype(np.float64)
        raise ConfigError(
            f"color_by = {color_by!r}: expected one of {', '.join(COLOR_BY)}, "
            "or one value per particle"
        )
    try:
        values = np.asarray(color_by, dtype=np.float64)
    except (TypeError, ValueError):
        raise ConfigError(
            f"color_by: expected one of {', '.join(COLOR_BY)} or numbers, one per particle"
        ) from None
    if values.ndim != 1 or values.shape[0] not in (packing.n_particles, len(placed)):
        raise ConfigError(
            f"color_by: {values.shape} values; expected one per drawn particle "
            f"({packing.n_particles}) or per placed particle ({len(placed)})"
        )
    if values.shape[0] == packing.n_particles:
        values = values[placed]
    return "value", values


def draw_packing(
    packing: Packing,
    ax: Axes | None = None,
    color_by: str | ArrayLike = "mineral",
    *,
    cmap: str = "viridis",
    edgecolor: str | None = None,
    linewidth: float = 0.0,
    legend: bool = True,
    colorbar: bool = True,
    label: str | None = None,
) -> PackingArtists:
    """Draw the placed particles of ``packing`` into ``ax`` (see :meth:`regopack.Packing.plot`)."""
    import matplotlib.pyplot as plt
    from matplotlib.axes import Axes
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Patch

    if ax is None:
        _, ax = plt.subplots(figsize=(5.0, 5.0))
    elif not isinstance(ax, Axes):
        raise ConfigError(f"ax: expected matplotlib axes, not {type(ax).__name__}")
    placed = np.flatnonzero(packing.placed).astype(np.int64)
    polygons, owner = _wrapped_images(packing, placed)
    rank = np.full(packing.n_particles, -1, dtype=np.int64)
    rank[placed] = np.arange(len(placed))
    coll = PolyCollection(polygons, closed=True, edgecolors=edgecolor or "face")
    coll.set_linewidth(linewidth if edgecolor is not None else 0.0)
    coll.set_rasterized(len(placed) > RASTERISE_ABOVE)
    drawn_legend = drawn_bar = None
    if isinstance(color_by, str) and color_by == "mineral":
        colours = mineral_colours(packing.mineral_names)
        coll.set_facecolor([colours[m] for m in packing.mineral[owner]])
        ax.add_collection(coll)
        if legend:
            counts = np.bincount(
                packing.mineral[placed], minlength=len(packing.mineral_names)
            ).tolist()
            handles = [
                Patch(facecolor=c, label=f"{_escape(name)} ({counts[k]:,})")
                for k, (name, c) in enumerate(zip(packing.mineral_names, colours, strict=True))
            ]
            drawn_legend = ax.legend(
                handles=handles, loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False
            )
    else:
        name, values = _values(packing, color_by, placed)
        coll.set_array(np.asarray(values)[rank[owner]])
        coll.set_cmap(cmap)
        ax.add_collection(coll)
        if colorbar:
            drawn_bar = ax.figure.colorbar(coll, ax=ax, label=label or name, shrink=0.8)
    outline = np.asarray(packing.domain.outline(), dtype=np.float64)
    closed = np.vstack([outline, outline[:1]])
    (boundary,) = ax.plot(closed[:, 0], closed[:, 1], color="#333333", linewidth=0.8)
    xmin, xmax, ymin, ymax = (float(b) for b in packing.domain.bounds())
    ax.set_xlim(xmin, xmax)
    ax.set_ylim(ymin, ymax)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x ({length_unit(packing)})")
    ax.set_ylabel(f"y ({length_unit(packing)})")
    return PackingArtists(ax, coll, boundary, drawn_legend, drawn_bar)


def summary_line(packing: Packing) -> str:
    """One line: scene, seed, particles placed of drawn, area fraction and domain.

    Examples
    --------
    >>> from regopack.testing import packing_from_polygons
    >>> p = packing_from_polygons([[(0, 0), (1, 0), (1, 1), (0, 1)]], domain=(0, 2, 0, 2))
    >>> summary_line(p)
    'test, seed 0: 1 of 1 particles placed, φ = 0.250 in a 2 × 2 µm rectangle'
    """
    dom = packing.domain
    u = length_unit(packing)
    kind = str(dom.to_dict().get("kind", type(dom).__name__.lower()))
    if kind == "circle":
        where = f"a circle {dom.width:g} {u} across"
    elif kind == "polygon":
        where = f"a polygon {dom.width:g} × {dom.height:g} {u}"
    elif kind == "periodic":
        where = f"a periodic {dom.width:g} × {dom.height:g} {u} rectangle"
    else:
        where = f"a {dom.width:g} × {dom.height:g} {u} {kind}"
    area = float(packing.area()[packing.placed].sum())
    phi = area / dom.area if dom.area > 0 else float("nan")
    name = packing.scene.get("name", "packing")
    return (
        f"{name}, seed {packing.seed}: {packing.n_placed:,} of {packing.n_particles:,} "
        f"particles placed, φ = {phi:.3f} in {where}"
    )


def packing_png(packing: Packing, size: float = 4.0, dpi: int = 72) -> bytes:
    """Return a small PNG picture of the packing coloured by mineral (for notebooks)."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(size * 1.45, size))
    ax = fig.add_subplot()
    draw_packing(packing, ax)
    ax.set_title(_escape(summary_line(packing)), fontsize=7)
    fig.set_layout_engine("constrained")
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()

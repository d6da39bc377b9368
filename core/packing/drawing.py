"""Drawing a packing with matplotlib: :meth:`regopack.Packing.plot` and the notebook pictures.

A 2D packing is drawn whole; a 3D packing by a planar section
(:func:`section_polygons` cuts every placed solid with an axis-aligned plane
into convex polygons), drawn as the 2D packings are. :func:`draw_view` renders
the solids that can be seen from outside a box (those within a largest
diameter of its three visible faces) with matplotlib's 3D axes, shaded by the
angle of each face to the light; :func:`draw_section` draws a section in the
style of the section exporter.
"""

from __future__ import annotations

import io
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from regopack.base.colours import mineral_colours
from regopack.base.errors import ConfigError
from regopack.base.units import length_unit
from regopack.geometry.domain import Cylinder

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.collections import PolyCollection
    from matplotlib.colorbar import Colorbar
    from matplotlib.legend import Legend
    from matplotlib.lines import Line2D

    from regopack.geometry.domain import Box
    from regopack.packing.core import Packing

__all__ = [
    "COLOR_BY",
    "PackingArtists",
    "draw_packing",
    "draw_section",
    "draw_view",
    "packing_png",
    "section_polygons",
    "summary_line",
]

FloatArray = NDArray[np.float64]

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
        periodic domain by the images of those that reach past a side; of a
        3D packing, one per solid the section cuts.
    boundary
        The domain's outline (of a 3D packing, the section's rectangle).
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
    axis: int = 1,
    at: float | None = None,
) -> PackingArtists:
    """Draw the placed particles of ``packing`` into ``ax`` (see :meth:`regopack.Packing.plot`).

    A 3D packing is drawn by its section with the plane ``x[axis] = at``
    (:func:`section_polygons`; default: the vertical plane through the box's
    centre); ``axis`` and ``at`` are ignored in 2D.
    """
    import matplotlib.pyplot as plt
    from matplotlib.axes import Axes
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Patch

    if ax is None:
        _, ax = plt.subplots(figsize=(5.0, 5.0))
    elif not isinstance(ax, Axes):
        raise ConfigError(f"ax: expected matplotlib axes, not {type(ax).__name__}")
    placed = np.flatnonzero(packing.placed).astype(np.int64)
    if packing.dimension == 3:
        if axis not in (0, 1, 2):
            raise ConfigError(f"axis = {axis!r}: expected 0, 1 or 2 (the normal of the section)")
        polygons, owner = section_polygons(packing, axis, at)
        keep = [a for a in range(3) if a != axis]
        box = packing.domain.bounds().reshape(3, 2)
        (x0, x1), (y0, y1) = box[keep[0]], box[keep[1]]
        outline = np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], dtype=np.float64)
        names = AXES[keep[0]], AXES[keep[1]]
    else:
        polygons, owner = _wrapped_images(packing, placed)
        outline = np.asarray(packing.domain.outline(), dtype=np.float64)
        x0, x1, y0, y1 = (float(b) for b in packing.domain.bounds())
        names = "x", "y"
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
    closed = np.vstack([outline, outline[:1]])
    (boundary,) = ax.plot(closed[:, 0], closed[:, 1], color="#333333", linewidth=0.8)
    ax.set_xlim(float(x0), float(x1))
    ax.set_ylim(float(y0), float(y1))
    ax.set_aspect("equal")
    ax.set_xlabel(f"{names[0]} ({length_unit(packing)})")
    ax.set_ylabel(f"{names[1]} ({length_unit(packing)})")
    return PackingArtists(ax, coll, boundary, drawn_legend, drawn_bar)


def summary_line(packing: Packing) -> str:
    """One line: scene, seed, particles placed of drawn, area or volume fraction and domain.

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
    if packing.dimension == 3:
        size = " × ".join(f"{s:g}" for s in dom.size)
        where = f"a {size} {u} {'periodic box' if dom.periodic else 'box'}"
        name = packing.scene.get("name", "packing")
        return (
            f"{name}, seed {packing.seed}: {packing.n_placed:,} of {packing.n_particles:,} "
            f"particles placed, φ = {packing.phi:.3f} in {where}"
        )
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


AXES = "xyz"
CIRCLE_SEGMENTS = 64
"""Segments of a sphere's circular section."""


def _convex_hull_2d(points: FloatArray) -> FloatArray:
    """Counter-clockwise hull of 2D points (monotone chain).

    Points within 1e-12 of the points' spread of each other count as one.
    """
    scale = float(np.ptp(points, axis=0).max()) if points.shape[0] else 0.0
    if scale > 0:
        pts = np.unique(np.round(points / scale, 12), axis=0) * scale
    else:
        pts = np.unique(points, axis=0)
    if pts.shape[0] < 3:
        return pts
    pts = pts[np.lexsort((pts[:, 1], pts[:, 0]))]

    def half(seq: FloatArray) -> list[FloatArray]:
        out: list[FloatArray] = []
        for p in seq:
            while len(out) >= 2:
                a, b = out[-2], out[-1]
                if (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) > 0:
                    break
                out.pop()
            out.append(p)
        return out

    lower = half(pts)
    upper = half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def section_polygons(
    packing: Packing[Box], axis: int = 1, at: float | None = None
) -> tuple[list[FloatArray], NDArray[np.int64]]:
    """Outlines of the placed solids cut by the plane ``x[axis] = at``.

    Parameters
    ----------
    packing
        The 3D packing.
    axis
        0, 1 or 2: the plane's normal (default y: a vertical section).
    at
        Position of the plane (default: the box's centre).

    Returns
    -------
    polygons, particles
        One ``(k, 2)`` counter-clockwise outline per cut solid, in the plane's
        coordinates (the other two axes in order), and the index of its particle.
    """
    if axis not in (0, 1, 2):
        raise ValueError(f"axis must be 0, 1 or 2, not {axis!r}")
    box = packing.domain
    if at is None:
        at = box.center[axis]
    keep = [a for a in range(3) if a != axis]
    solids = packing.solids
    rho = solids.rounding_radius
    polygons: list[FloatArray] = []
    owners: list[int] = []
    for j in packing.placed_in_order():
        j = int(j)
        c = packing.centre[j]
        if solids.face_offsets[j] == solids.face_offsets[j + 1]:  # a sphere
            h = at - c[axis]
            if abs(h) >= rho[j]:
                continue
            s = np.sqrt(rho[j] ** 2 - h * h)
            ang = 2 * np.pi * np.arange(CIRCLE_SEGMENTS) / CIRCLE_SEGMENTS
            polygons.append(
                np.column_stack([c[keep[0]] + s * np.cos(ang), c[keep[1]] + s * np.sin(ang)])
            )
            owners.append(j)
            continue
        pts = packing.world_vertices(j)
        side = pts[:, axis] - at
        if side.min() >= 0 or side.max() <= 0:
            continue
        _, loops = solids.solid(j)
        cuts = []
        for loop in loops:
            a = side[loop]
            b = side[np.roll(loop, -1)]
            cross = (a < 0) != (b < 0)
            if not cross.any():
                continue
            pa = pts[loop][cross]
            pb = pts[np.roll(loop, -1)][cross]
            t = (a[cross] / (a[cross] - b[cross]))[:, None]
            cuts.append(pa + t * (pb - pa))
        if not cuts:
            continue
        hull = _convex_hull_2d(np.vstack(cuts)[:, keep])
        if hull.shape[0] >= 3:
            polygons.append(hull)
            owners.append(j)
    return polygons, np.asarray(owners, dtype=np.int64)


def draw_section(
    packing: Packing[Box], ax: Axes, axis: int = 1, at: float | None = None, **style: Any
) -> None:
    """Draw the section of ``packing`` by the plane ``x[axis] = at`` on ``ax``, by mineral."""
    from matplotlib.collections import PolyCollection
    from matplotlib.patches import Patch

    polygons, owners = section_polygons(packing, axis, at)
    colours = mineral_colours(packing.mineral_names)
    faces = [colours[int(packing.mineral[j])] for j in owners]
    ax.add_collection(
        PolyCollection(polygons, facecolors=faces, edgecolors="black", linewidths=0.2, **style)
    )
    b = packing.domain.bounds().reshape(3, 2)
    keep = [a for a in range(3) if a != axis]
    _wall_section(packing, ax, axis, at)
    ax.set_xlim(*b[keep[0]])
    ax.set_ylim(*b[keep[1]])
    ax.set_aspect("equal")
    unit = length_unit(packing)
    ax.set_xlabel(f"{AXES[keep[0]]} ({unit})")
    ax.set_ylabel(f"{AXES[keep[1]]} ({unit})")
    present = sorted({int(packing.mineral[j]) for j in owners})
    ax.legend(
        handles=[Patch(color=colours[m], label=packing.mineral_names[m]) for m in present],
        loc="upper left",
        bbox_to_anchor=(1.01, 1.0),
        frameon=False,
    )


def _wall_section(packing: Packing, ax: Axes, axis: int, at: float | None) -> None:
    """Draw a cylinder's wall where the plane ``x[axis] = at`` cuts it (a box: nothing)."""
    dom = packing.domain
    if not isinstance(dom, Cylinder):
        return
    at = dom.center[axis] if at is None else at
    style: dict[str, Any] = {"color": "black", "linewidth": 0.8}
    if axis == 2:
        t = np.linspace(0.0, 2.0 * np.pi, 181)
        ax.plot(dom.cx + dom.radius * np.cos(t), dom.cy + dom.radius * np.sin(t), **style)
        return
    off = at - (dom.cx, dom.cy)[axis]
    if abs(off) >= dom.radius:
        return
    half = float(np.sqrt(dom.radius**2 - off**2))
    mid = (dom.cy, dom.cx)[axis]  # the other horizontal coordinate of the axis
    for x in (mid - half, mid + half):
        ax.plot([x, x], [dom.zmin, dom.zmax], **style)


def draw_view(packing: Packing[Box], ax: Any, depth: float | None = None) -> int:
    """Render the solids seen from outside the box on the 3D axes ``ax``; return how many.

    The solids within ``depth`` (default: the largest circumradius, twice)
    of the faces ``x = xmax``, ``y = ymin`` and ``z = zmax`` are drawn, their
    faces shaded by the angle to a light from the viewer's side; in a
    cylinder, those within ``depth`` of the lid or of the half of the side
    wall that faces the viewer (towards ``+x, -y``).
    """
    from mpl_toolkits.mplot3d.art3d import Poly3DCollection

    box = packing.domain
    solids = packing.solids
    if depth is None:
        depth = 2.0 * float(solids.circumradius.max()) if packing.n_particles else 0.0
    colours = mineral_colours(packing.mineral_names)
    light = np.array([0.6, -0.5, 0.8])
    light /= np.linalg.norm(light)
    polys, face_colours = [], []
    shown = 0
    for j in packing.placed_in_order():
        j = int(j)
        c = packing.centre[j]
        if isinstance(box, Cylinder):
            dx, dy = c[0] - box.cx, c[1] - box.cy
            near_side = math.hypot(dx, dy) > box.radius - depth and dx - dy >= 0
            if not (near_side or c[2] > box.zmax - depth):
                continue
        elif not (c[0] > box.xmax - depth or c[1] < box.ymin + depth or c[2] > box.zmax - depth):
            continue
        if solids.face_offsets[j] == solids.face_offsets[j + 1]:
            continue  # spheres are not rendered here
        shown += 1
        pts = packing.world_vertices(j)
        _, loops = solids.solid(j)
        base = np.array(_rgb(colours[int(packing.mineral[j])]))
        f0 = int(solids.face_offsets[j])
        for f, loop in enumerate(loops):
            n = solids.normals[f0 + f]
            shade = 0.45 + 0.55 * max(float(n @ light), 0.0)
            polys.append(pts[loop])
            face_colours.append(tuple(np.clip(base * shade, 0, 1)))
    ax.add_collection3d(
        Poly3DCollection(polys, facecolors=face_colours, edgecolors=(0, 0, 0, 0.3), linewidths=0.1)
    )
    b = box.bounds().reshape(3, 2)
    ax.set_xlim(*b[0])
    ax.set_ylim(*b[1])
    ax.set_zlim(*b[2])
    ax.set_box_aspect(tuple(float(hi - lo) for lo, hi in b))
    ax.view_init(elev=22, azim=-60)
    unit = length_unit(packing)
    ax.set_xlabel(f"x ({unit})")
    ax.set_ylabel(f"y ({unit})")
    ax.set_zlabel(f"z ({unit})")
    return shown


def _rgb(colour: Any) -> tuple[float, float, float]:
    from matplotlib.colors import to_rgb

    r, g, b = to_rgb(colour)
    return (r, g, b)

"""Figures of 3D packings: a planar section drawn as the 2D figures are, and a rendered view.

:func:`section_polygons` cuts every placed solid with an axis-aligned plane
and returns the cut outlines (convex polygons); :func:`draw_section` draws
them coloured by mineral, as :func:`regopack.packing.drawing.draw_packing` draws a 2D
packing. :func:`draw_view` renders the solids that can be seen from outside
the box (those within a largest diameter of its three visible faces) with
matplotlib's 3D axes, shaded by the angle of each face to the light.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from regopack.base.colours import mineral_colours
from regopack.base.units import length_unit
from regopack.geometry.domain import Box
from regopack.packing.core import Packing

if TYPE_CHECKING:
    from matplotlib.axes import Axes

FloatArray = NDArray[np.float64]

__all__ = ["draw_section", "draw_view", "section_polygons"]

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


def draw_view(packing: Packing[Box], ax: Any, depth: float | None = None) -> int:
    """Render the solids seen from outside the box on the 3D axes ``ax``; return how many.

    The solids within ``depth`` (default: the largest circumradius, twice)
    of the faces ``x = xmax``, ``y = ymin`` and ``z = zmax`` are drawn, their
    faces shaded by the angle to a light from the viewer's side.
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
        if not (c[0] > box.xmax - depth or c[1] < box.ymin + depth or c[2] > box.zmax - depth):
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

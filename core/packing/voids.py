"""Connected voids: test whether the free space of a packing spans a window.

The free space of a window is rasterised on a square grid (a pixel is free
when its centre lies in no particle), the free pixels are grouped into
clusters of 4-connected pixels (:func:`scipy.ndimage.label`), and the voids
are called *connected* when the largest cluster touches two opposite sides of
the window (left and right, or bottom and top).

:func:`void_metrics` returns ``void_spans`` (that test) and
``largest_void_fraction`` (the largest cluster's share of the window's area).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
from matplotlib.path import Path as MplPath
from numpy.typing import NDArray
from scipy import ndimage

from regopack.base.errors import GeometryError
from regopack.geometry.domain import Rectangle
from regopack.packing.core import Packing

__all__ = ["MAX_PIXELS_PER_SIDE", "free_space_mask", "spans", "void_metrics"]

MAX_PIXELS_PER_SIDE = 4096
"""The grid is coarsened so that neither side has more pixels than this."""


def free_space_mask(
    polygons: Sequence[NDArray[np.float64]],
    window: tuple[float, float, float, float],
    pixel: float,
) -> NDArray[np.bool_]:
    """Rasterise the free space of ``window`` = (xmin, xmax, ymin, ymax).

    Parameters
    ----------
    polygons
        Particle outlines in absolute coordinates, each ``(k, 2)``.
    window
        The window's bounds.
    pixel
        Side of a pixel (coarsened to keep at most :data:`MAX_PIXELS_PER_SIDE`
        pixels per side).

    Returns
    -------
    numpy.ndarray
        ``(ny, nx)`` boolean mask, True where the pixel centre is in no polygon;
        row 0 is at the bottom of the window.
    """
    xmin, xmax, ymin, ymax = window
    width, height = xmax - xmin, ymax - ymin
    if not (width > 0 and height > 0 and pixel > 0):
        return np.zeros((0, 0), dtype=bool)
    pixel = max(pixel, width / MAX_PIXELS_PER_SIDE, height / MAX_PIXELS_PER_SIDE)
    nx, ny = max(1, math.ceil(width / pixel)), max(1, math.ceil(height / pixel))
    dx, dy = width / nx, height / ny
    xs = xmin + (np.arange(nx) + 0.5) * dx
    ys = ymin + (np.arange(ny) + 0.5) * dy
    free = np.ones((ny, nx), dtype=bool)
    for poly in polygons:
        px0, py0 = poly.min(axis=0)
        px1, py1 = poly.max(axis=0)
        i0 = max(0, math.floor((px0 - xmin) / dx - 0.5))
        i1 = min(nx, math.ceil((px1 - xmin) / dx + 0.5))
        j0 = max(0, math.floor((py0 - ymin) / dy - 0.5))
        j1 = min(ny, math.ceil((py1 - ymin) / dy + 0.5))
        if i0 >= i1 or j0 >= j1:
            continue
        gx, gy = np.meshgrid(xs[i0:i1], ys[j0:j1])
        points = np.column_stack([gx.ravel(), gy.ravel()])
        inside = MplPath(poly).contains_points(points).reshape(gy.shape)
        free[j0:j1, i0:i1] &= ~inside
    return free


def spans(cluster: NDArray[np.bool_]) -> bool:
    """Tell whether ``cluster`` touches two opposite sides of its grid."""
    if cluster.size == 0:
        return False
    horizontal = bool(cluster[:, 0].any() and cluster[:, -1].any())
    vertical = bool(cluster[0, :].any() and cluster[-1, :].any())
    return horizontal or vertical


def void_metrics(
    packing: Packing,
    window: tuple[float, float, float, float] | None = None,
    resolution: float = 0.25,
) -> dict[str, Any]:
    """Measure whether the voids of a packing connect across a window.

    Parameters
    ----------
    packing
        The packing.
    window
        (xmin, xmax, ymin, ymax); default: the interior window, one largest
        particle diameter inside the walls.
    resolution
        Pixel side as a fraction of the smallest placed particle's equivalent
        diameter.

    Returns
    -------
    dict
        ``void_spans`` (bool), ``largest_void_fraction`` (largest free cluster's
        area over the window's area), ``void_clusters`` (number of clusters) and
        ``void_pixel`` (pixel side used).

    Examples
    --------
    A window with no particle is one free cluster that spans it:

    >>> free = free_space_mask([], (0.0, 1.0, 0.0, 1.0), 0.1)
    >>> bool(free.all()), spans(free)
    (True, True)
    """
    placed = np.flatnonzero(packing.placed)
    if window is None:
        d_max = 2.0 * float(packing.radius.max()) if packing.radius.size else 0.0
        w = packing.domain.interior(d_max)
        if not isinstance(w, Rectangle) or packing.domain.periodic:
            raise GeometryError(
                f"voids are measured in the interior window of a walled rectangle; the "
                f"domain is a {packing.domain.kind}: pass window=(xmin, xmax, ymin, ymax)"
            )
        window = (w.xmin, w.xmax, w.ymin, w.ymax)
    if placed.size:
        d_min = 2.0 * float(packing.radius[placed].min())
    else:
        d_min = 2.0 * float(packing.radius.min()) if packing.radius.size else 1.0
    pixel = resolution * d_min
    free = free_space_mask(packing.polygons(placed), window, pixel)
    nan = float("nan")
    if free.size == 0:
        return {
            "void_spans": False,
            "largest_void_fraction": nan,
            "void_clusters": 0,
            "void_pixel": pixel,
        }
    labels, n = ndimage.label(free)
    if n == 0:
        return {
            "void_spans": False,
            "largest_void_fraction": 0.0,
            "void_clusters": 0,
            "void_pixel": pixel,
        }
    sizes = np.bincount(labels.ravel())[1:]
    largest = int(np.argmax(sizes)) + 1
    cluster = labels == largest
    return {
        "void_spans": spans(cluster),
        "largest_void_fraction": float(sizes[largest - 1]) / free.size,
        "void_clusters": int(n),
        "void_pixel": float(max(pixel, (window[1] - window[0]) / MAX_PIXELS_PER_SIDE)),
    }

"""Raster images of a packing for image-based pore studies (exporter ``image``).

The placed particles are sampled on a grid of square pixels (2D) or cubic
voxels (3D): a pixel or voxel belongs to a particle when its centre lies in
the particle (on or inside a sharp outline or polyhedron; within the rounding
radius of the core of a rounded one, so disks and spheres are exact). The
grid covers the domain's bounding box from its top-left corner; row 0 is the
top of the domain (largest y), column 0 its left side (smallest x). A 3D
image is a stack of such layers, ``[layer, row, column]``, layer 0 at the
bottom (smallest z): every layer is the 2D image of a horizontal section seen
from above. Pixels whose centre lies outside the domain (around a circle or
polygon, or past a side that the pixel size does not divide) have their own
value in every image and are neither solid nor pore; so do the voxels
around a walled cylinder (outside its circle, in every layer), so that the
porosity of the image is that of the cylinder. In a periodic domain a
particle that crosses a side is drawn on both sides.

>>> from regopack.testing import packing_from_polygons
>>> p = packing_from_polygons([[(1, 1), (3, 1), (3, 3), (1, 3)]], domain=(0, 4, 0, 4))
>>> image = rasterise(p, pixel_size=1.0)
>>> image.labels.tolist()
[[0, 0, 0, 0], [0, 1, 1, 0], [0, 1, 1, 0], [0, 0, 0, 0]]
>>> float(image.phi)
0.25

A sphere of radius 1 at the centre of a 2-µm cube, in voxels of 0.5 µm:

>>> from regopack.geometry.domain import Box
>>> ball = Packing.of_spheres([[1, 1, 1]], [1.0], Box(0, 2, 0, 2, 0, 2))
>>> voxels = rasterise(ball, pixel_size=0.5)
>>> voxels.labels.shape, int(voxels.solid.sum())
((4, 4, 4), 32)
"""

from __future__ import annotations

import io
import itertools
import json
import math
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from pydantic import BaseModel, ConfigDict, Field

from regopack.base.errors import ExportError
from regopack.geometry.domain import Box, Cylinder, Domain, PeriodicRectangle, Rectangle
from regopack.packing.core import Packing, _atomic_file, _finite_or_none
from regopack.registry.hookspecs import hookimpl
from regopack.registry.interfaces import Analyzer, Exporter
from regopack.registry.plugin_types import ExporterSpec

__all__ = [
    "IMAGE_FORMAT",
    "MAX_PIXELS_LIMIT",
    "ImageConfig",
    "ImageExporter",
    "PixelGrid",
    "RasterImage",
    "default_pixel_size",
    "image_paths",
    "pixel_grid",
    "rasterise",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

IMAGE_FORMAT = "regopack-image"
"""Value of ``format`` in the ``<stem>_image.json`` file of an image export."""

DEFAULT_MAX_PIXELS = 2**28
"""Default largest image (pixels or voxels): about 16 000 × 16 000, or 645³."""

MAX_PIXELS_LIMIT = 2**29
"""Largest ``max_pixels`` allowed (the label TIFF stays below the 4 GiB of a classic TIFF)."""

BYTES_PER_PIXEL = 10
"""Memory an export needs per pixel or voxel, roughly (labels, masks and one file's buffer)."""

OUTSIDE_LABEL = -1
"""Particle label of a pixel outside the domain (0 is void, ``j + 1`` particle ``j``)."""

PNG_VOID, PNG_SOLID, PNG_OUTSIDE = 0, 255, 128
"""Grey values of the binary PNG."""

PORE, SOLID, OUTSIDE = 1, 0, 2
"""Values of the ``.npy`` phase image (PoreSpy's convention: 1 pore, 0 solid, others ignored)."""

MINERAL_OUTSIDE = 255
"""Value of the minerals PNG outside the domain (0 is void, ``k + 1`` mineral ``k``)."""

_SIDE_TOL = 1e-9
"""Slack, in pixels, before a domain side that falls on a pixel edge adds a column or row."""

_ROWS_PER_CHUNK = 512
"""Rows of the domain mask computed at once (bounds the memory of the point tests)."""

_CHUNK = 1 << 22
"""Work (lines times corners or faces, plus their pixels) that one scanline fill handles at once."""


class ImageConfig(BaseModel):
    """Parameters of the image exporter."""

    model_config = ConfigDict(extra="forbid", strict=True)

    pixel_size: float = Field(
        0.0,
        ge=0,
        allow_inf_nan=False,
        description=(
            "Side of a square pixel (a cubic voxel in 3D) in the length unit; 0 takes d_min/10 "
            "(d_min the smallest placed particle's equivalent diameter), made just small enough "
            "that a whole number of pixels spans the domain's width."
        ),
    )
    max_pixels: int = Field(
        DEFAULT_MAX_PIXELS,
        gt=0,
        le=MAX_PIXELS_LIMIT,
        description=(
            "Largest image, in pixels (voxels in 3D); a larger one is refused before anything "
            "is allocated (an export needs about 10 bytes of memory a pixel)."
        ),
    )


@dataclass(frozen=True)
class PixelGrid:
    """Square pixels over a domain's bounding box, row 0 at the top; in 3D, layers of them.

    The centre of pixel ``(row, col)`` is ``(x_left + (col + 0.5) size,
    y_top - (row + 0.5) size)``. A 3D grid (``n_layers > 0``) stacks
    ``n_layers`` such layers of cubic voxels upward from ``z_bottom``: voxel
    ``(layer, row, col)`` has that centre and ``z = z_bottom + (layer + 0.5) size``.
    """

    x_left: float
    y_top: float
    size: float
    n_rows: int
    n_cols: int
    z_bottom: float = 0.0
    n_layers: int = 0

    @property
    def dimension(self) -> int:
        """2 for pixels, 3 for voxels."""
        return 3 if self.n_layers else 2

    @property
    def shape(self) -> tuple[int, ...]:
        """``(n_rows, n_cols)``, or ``(n_layers, n_rows, n_cols)`` in 3D."""
        if self.n_layers:
            return (self.n_layers, self.n_rows, self.n_cols)
        return (self.n_rows, self.n_cols)

    def x(self, cols: NDArray[Any]) -> FloatArray:
        """Return the x of the centres of the columns ``cols``."""
        out: FloatArray = self.x_left + (np.asarray(cols, dtype=np.float64) + 0.5) * self.size
        return out

    def y(self, rows: NDArray[Any]) -> FloatArray:
        """Return the y of the centres of the rows ``rows``."""
        out: FloatArray = self.y_top - (np.asarray(rows, dtype=np.float64) + 0.5) * self.size
        return out

    def z(self, layers: NDArray[Any]) -> FloatArray:
        """Return the z of the centres of the layers ``layers`` (3D)."""
        out: FloatArray = self.z_bottom + (np.asarray(layers, dtype=np.float64) + 0.5) * self.size
        return out

    def extent(self) -> tuple[float, float, float, float]:
        """``(left, right, bottom, top)``, matplotlib's ``extent`` (of a layer in 3D)."""
        return (
            self.x_left,
            self.x_left + self.n_cols * self.size,
            self.y_top - self.n_rows * self.size,
            self.y_top,
        )

    def bounds(self) -> tuple[float, ...]:
        """``(xmin, xmax, ymin, ymax)`` of the image, and ``zmin, zmax`` in 3D."""
        if not self.n_layers:
            return self.extent()
        return (*self.extent(), self.z_bottom, self.z_bottom + self.n_layers * self.size)


@dataclass(frozen=True)
class RasterImage:
    """A packing sampled on a :class:`PixelGrid`.

    Attributes
    ----------
    grid
        The pixels (voxels).
    labels
        ``grid.shape`` int32, ``(n_rows, n_cols)`` or ``(n_layers, n_rows,
        n_cols)``: 0 void, ``j + 1`` particle of draw index ``j``,
        :data:`OUTSIDE_LABEL` outside the domain.
    mineral
        Mineral index of every particle (the packing's ``mineral``).
    """

    grid: PixelGrid
    labels: NDArray[np.int32]
    mineral: NDArray[np.int64]

    @property
    def inside(self) -> BoolArray:
        """Mask of the pixels inside the domain."""
        out: BoolArray = self.labels != OUTSIDE_LABEL
        return out

    @property
    def solid(self) -> BoolArray:
        """Mask of the pixels covered by a particle."""
        out: BoolArray = self.labels > 0
        return out

    @property
    def middle_layer(self) -> int:
        """Layer drawn in the PNG files of a 3D image: ``n_layers // 2`` (0 in 2D)."""
        return self.grid.n_layers // 2

    def layer(self, k: int) -> RasterImage:
        """Return layer ``k`` of a 3D image as a 2D image: the section at z of its centres."""
        g = self.grid
        flat = PixelGrid(g.x_left, g.y_top, g.size, g.n_rows, g.n_cols)
        return RasterImage(flat, self.labels[k], self.mineral)

    @property
    def phi(self) -> float:
        """Solid fraction of the image: solid pixels over the pixels inside the domain."""
        inside = int(np.count_nonzero(self.inside))
        return int(np.count_nonzero(self.solid)) / inside if inside else math.nan

    def binary(self) -> NDArray[np.uint8]:
        """Grey image: solid :data:`PNG_SOLID`, void 0, outside :data:`PNG_OUTSIDE`."""
        out = np.full(self.labels.shape, PNG_VOID, dtype=np.uint8)
        out[self.labels > 0] = PNG_SOLID
        out[self.labels == OUTSIDE_LABEL] = PNG_OUTSIDE
        return out

    def phases(self) -> NDArray[np.uint8]:
        """Phase image in PoreSpy's convention: :data:`PORE`, :data:`SOLID`, :data:`OUTSIDE`."""
        out = np.full(self.labels.shape, PORE, dtype=np.uint8)
        out[self.labels > 0] = SOLID
        out[self.labels == OUTSIDE_LABEL] = OUTSIDE
        return out

    def minerals(self) -> NDArray[np.uint8]:
        """Mineral image: 0 void, ``k + 1`` mineral ``k``, :data:`MINERAL_OUTSIDE` outside.

        Raises
        ------
        ExportError
            When a mineral index does not fit below :data:`MINERAL_OUTSIDE`.
        """
        _check_minerals(int(self.mineral.max(initial=-1)) + 1)
        lut = np.empty(self.mineral.shape[0] + 2, dtype=np.uint8)
        lut[0] = MINERAL_OUTSIDE  # label -1, shifted to 0
        lut[1] = 0
        lut[2:] = self.mineral + 1
        out: NDArray[np.uint8] = lut[self.labels + 1]
        return out


def _check_minerals(n_minerals: int) -> None:
    if n_minerals >= MINERAL_OUTSIDE:
        raise ExportError(
            f"the minerals image holds up to {MINERAL_OUTSIDE - 1} minerals; this packing "
            f"has {n_minerals}"
        )


# ---------------------------------------------------------------------------
# the grid


def default_pixel_size(packing: Packing) -> float:
    """d_min/10, d_min the smallest placed particle's equivalent diameter ``2 radius``.

    The equivalent diameter is that of the disk of equal area in 2D, of the
    sphere of equal volume in 3D.

    Raises
    ------
    ExportError
        When no particle is placed.
    """
    placed = packing.placed
    if not placed.any():
        raise ExportError(
            "pixel_size = 0 takes d_min/10 of the placed particles, but none is placed; "
            "set pixel_size > 0"
        )
    return 2.0 * float(packing.radius[placed].min()) / 10.0


def _count(length: float, size: float) -> int:
    """Pixels of side ``size`` that cover ``length`` (a side on a pixel edge adds none)."""
    return max(1, math.ceil(length / size - _SIDE_TOL))


def pixel_grid(
    packing: Packing, pixel_size: float = 0.0, max_pixels: int = DEFAULT_MAX_PIXELS
) -> PixelGrid:
    """Return the pixels (voxels) of an image of ``packing``, checked against ``max_pixels``.

    Parameters
    ----------
    packing
        The packing (its domain and, for the default size, its particles); a
        3D packing gives a grid of voxels.
    pixel_size
        Side of a pixel or voxel; 0 takes :func:`default_pixel_size`,
        reduced so that a whole number of pixels spans the domain's width.
    max_pixels
        Largest number of pixels (voxels) allowed.

    Raises
    ------
    ExportError
        One line, when ``pixel_size`` is negative or not finite, or the image
        would have more than ``max_pixels`` pixels.
    """
    if not (math.isfinite(pixel_size) and pixel_size >= 0):
        raise ExportError(f"pixel_size = {pixel_size!r}: a pixel size is a finite number > 0")
    b = [float(v) for v in packing.domain.bounds()]
    sides = [b[2 * a + 1] - b[2 * a] for a in range(len(b) // 2)]
    size = float(pixel_size)
    if size == 0:
        size = sides[0] / _count(sides[0], default_pixel_size(packing))
    counts = [_count(side, size) for side in sides]
    total = math.prod(counts)
    if total > max_pixels:
        what = "voxels" if len(sides) == 3 else "pixels"
        smallest = (math.prod(sides) / max_pixels) ** (1.0 / len(sides))
        raise ExportError(
            f"pixel_size = {size:.6g} gives an image of {' x '.join(map(str, counts))} = "
            f"{total} {what}, more than max_pixels = {max_pixels} (about {BYTES_PER_PIXEL} "
            f"bytes of memory a pixel); use pixel_size >= {smallest:.3g} or raise max_pixels "
            f"(at most {MAX_PIXELS_LIMIT})"
        )
    if len(sides) == 3:
        return PixelGrid(b[0], b[3], size, counts[1], counts[0], b[4], counts[2])
    return PixelGrid(b[0], b[3], size, counts[1], counts[0])


# ---------------------------------------------------------------------------
# the rasteriser


def _inside_polygon(v: FloatArray, xs: FloatArray, ys: FloatArray) -> BoolArray:
    """Pixel centres ``(ys x xs)`` on or inside the counter-clockwise convex polygon ``v``."""
    e = np.roll(v, -1, axis=0) - v
    # outward normal of a counter-clockwise edge: (ey, -ex); inside: n . (p - v) <= 0
    along_x = e[:, 1, None] * (xs[None, :] - v[:, 0, None])
    along_y = -e[:, 0, None] * (ys[None, :] - v[:, 1, None])
    out: BoolArray = np.all(along_y[:, :, None] + along_x[:, None, :] <= 0.0, axis=0)
    return out


def _near_core(v: FloatArray, rho: float, xs: FloatArray, ys: FloatArray) -> BoolArray:
    """Pixel centres within ``rho`` of the convex core ``v`` (a point, a segment or a polygon)."""
    dx = xs[None, None, :] - v[:, 0, None, None]
    dy = ys[None, :, None] - v[:, 1, None, None]
    if v.shape[0] == 1:
        out: BoolArray = (dx[0] * dx[0] + dy[0] * dy[0]) <= rho * rho
        return out
    e = np.roll(v, -1, axis=0)[:, :, None, None] - v[:, :, None, None]
    length2 = e[:, 0] * e[:, 0] + e[:, 1] * e[:, 1]
    t = np.clip((dx * e[:, 0] + dy * e[:, 1]) / length2, 0.0, 1.0)
    gx, gy = dx - t * e[:, 0], dy - t * e[:, 1]
    out = np.any(gx * gx + gy * gy <= rho * rho, axis=0)
    if v.shape[0] >= 3:
        out |= _inside_polygon(v, xs, ys)
    return out


def _bounds(packing: Packing, idx: IntArray) -> tuple[FloatArray, FloatArray]:
    """Lowest and highest corners ``(n, dimension)`` of the particles ``idx``, rounding included."""
    v, starts = packing.vertices, packing.offsets[:-1]
    lo = np.minimum.reduceat(v, starts, axis=0)
    hi = np.maximum.reduceat(v, starts, axis=0)
    grow = packing.rounding_radius[idx, None]
    return lo[idx] + packing.centre[idx] - grow, hi[idx] + packing.centre[idx] + grow


def _copies(packing: Packing, grid: PixelGrid) -> tuple[IntArray, FloatArray, FloatArray]:
    """Draw index, offset ``(n, dimension)`` and shifted bounding box of every copy to draw.

    A walled domain has one copy per placed particle; in a periodic domain a
    particle that crosses a side has a copy shifted by a period for every
    side (edge, corner) of the image it reaches. Copies are in draw order.
    """
    idx = np.flatnonzero(packing.placed).astype(np.int64)
    lo, hi = _bounds(packing, idx)
    d = packing.domain
    if not d.periodic:
        return idx, np.zeros(lo.shape), np.stack([lo, hi], axis=1)
    edges = np.array(grid.bounds()).reshape(-1, 2)
    periods = [float(length) for length in d.period]
    rows, shifts = [], []
    for shift in itertools.product(*[(-length, 0.0, length) for length in periods]):
        near = np.all((hi + shift >= edges[:, 0]) & (lo + shift <= edges[:, 1]), axis=1)
        rows.append(np.flatnonzero(near))
        shifts.append(np.tile(shift, (rows[-1].shape[0], 1)))
    at = np.concatenate(rows)
    order = np.argsort(at, kind="stable")
    at, offset = at[order], np.concatenate(shifts)[order]
    return idx[at], offset, np.stack([lo[at] + offset, hi[at] + offset], axis=1)


def _row_span(box: FloatArray, grid: PixelGrid) -> tuple[IntArray, IntArray]:
    """Rows ``[r0, r1)`` whose centres may lie within the boxes' y range."""
    h = grid.size
    r0 = np.ceil((grid.y_top - box[:, 1, 1]) / h - 0.5)
    r1 = np.floor((grid.y_top - box[:, 0, 1]) / h - 0.5) + 1
    return (
        np.clip(r0, 0, grid.n_rows).astype(np.int64),
        np.clip(r1, 0, grid.n_rows).astype(np.int64),
    )


def _layer_span(box: FloatArray, grid: PixelGrid) -> tuple[IntArray, IntArray]:
    """Layers ``[k0, k1)`` whose centres may lie within the boxes' z range (3D)."""
    h = grid.size
    k0 = np.ceil((box[:, 0, 2] - grid.z_bottom) / h - 0.5)
    k1 = np.floor((box[:, 1, 2] - grid.z_bottom) / h - 0.5) + 1
    return (
        np.clip(k0, 0, grid.n_layers).astype(np.int64),
        np.clip(k1, 0, grid.n_layers).astype(np.int64),
    )


def _chunks(weight: IntArray) -> Iterator[slice]:
    """Consecutive slices of ``weight`` whose sums stay near :data:`_CHUNK`."""
    total = np.cumsum(weight)
    start = 0
    while start < weight.shape[0]:
        base = int(total[start - 1]) if start else 0
        stop = max(start + 1, int(np.searchsorted(total, base + _CHUNK, side="right")))
        yield slice(start, stop)
        start = stop


def _fill(
    labels: NDArray[np.int32],
    grid: PixelGrid,
    rows: IntArray,
    xl: FloatArray,
    xr: FloatArray,
    value: NDArray[np.int32],
) -> None:
    """Set the pixels of every row ``rows[i]`` whose centre x lies in ``[xl[i], xr[i]]``.

    In 3D a row is a line of voxels, ``layer * n_rows + row``.
    """
    h, x0 = grid.size, grid.x_left
    with np.errstate(invalid="ignore"):
        a = np.clip(np.ceil((xl - x0) / h - 0.5), 0, grid.n_cols)
        b = np.clip(np.floor((xr - x0) / h - 0.5) + 1, 0, grid.n_cols)
    keep = b > a  # False where a bound is NaN (an empty row)
    a, b = a[keep].astype(np.int64), b[keep].astype(np.int64)
    length = b - a
    if not length.size:
        return
    first = rows[keep] * grid.n_cols + a
    flat = np.repeat(first - (np.cumsum(length) - length), length)
    flat += np.arange(flat.shape[0], dtype=np.int64)
    labels.reshape(-1)[flat] = np.repeat(value[keep], length)


def _expand(r0: IntArray, r1: IntArray) -> tuple[IntArray, IntArray]:
    """Copy (position in ``r0``) and row of every row of every copy."""
    n_rows = np.maximum(r1 - r0, 0)
    copy = np.repeat(np.arange(r0.shape[0]), n_rows)
    row = np.arange(copy.shape[0], dtype=np.int64) - np.repeat(np.cumsum(n_rows) - n_rows, n_rows)
    return copy, r0[copy] + row


def _fill_polygons(
    labels: NDArray[np.int32], grid: PixelGrid, packing: Packing, j: IntArray, shift: FloatArray
) -> None:
    """Scanline fill of the sharp convex polygons ``j`` (offset by ``shift``)."""
    counts = packing.offsets[j + 1] - packing.offsets[j]
    width = int(counts.max())
    # pad every outline to ``width`` corners by repeating its last one (zero-length edges)
    corner = packing.offsets[j, None] + np.minimum(np.arange(width), counts[:, None] - 1)
    v = packing.vertices[corner] + (packing.centre[j] + shift)[:, None, :]
    e = np.roll(v, -1, axis=1) - v
    r0, r1 = _row_span(np.stack([v.min(axis=1), v.max(axis=1)], axis=1), grid)
    copy, row = _expand(r0, r1)
    y = grid.y(row)
    # inside every edge: e_y (x - v_x) <= e_x (y - v_y) with the outward normal (e_y, -e_x)
    a = e[copy, :, 1]
    c = e[copy, :, 0] * (y[:, None] - v[copy, :, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        bound = v[copy, :, 0] + c / a
    xl = np.where(a < 0, bound, -np.inf).max(axis=1)
    xr = np.where(a > 0, bound, np.inf).min(axis=1)
    xl[~np.all((a != 0) | (c >= 0), axis=1)] = np.nan  # above or below a horizontal edge
    _fill(labels, grid, row, xl, xr, (j + 1).astype(np.int32)[copy])


def _fill_disks(
    labels: NDArray[np.int32], grid: PixelGrid, packing: Packing, j: IntArray, shift: FloatArray
) -> None:
    """Scanline fill of the disks ``j``: one core point, grown by its rounding radius."""
    centre = packing.vertices[packing.offsets[j]] + packing.centre[j] + shift
    rho = packing.rounding_radius[j]
    box = np.stack([centre - rho[:, None], centre + rho[:, None]], axis=1)
    copy, row = _expand(*_row_span(box, grid))
    dy = grid.y(row) - centre[copy, 1]
    with np.errstate(invalid="ignore"):
        half = np.sqrt(rho[copy] ** 2 - dy * dy)  # NaN where the row misses the disk
    cx = centre[copy, 0]
    _fill(labels, grid, row, cx - half, cx + half, (j + 1).astype(np.int32)[copy])


def _fill_rounded(
    labels: NDArray[np.int32],
    grid: PixelGrid,
    packing: Packing,
    j: int,
    box: FloatArray,
    shift: FloatArray,
) -> None:
    """Pixel by pixel: centres within the rounding radius of the core of particle ``j``."""
    core = packing.vertices[packing.offsets[j] : packing.offsets[j + 1]] + packing.centre[j] + shift
    r0, r1 = (int(r[0]) for r in _row_span(box[None], grid))
    h = grid.size
    c0 = max(0, math.ceil((box[0, 0] - grid.x_left) / h - 0.5))
    c1 = min(grid.n_cols, math.floor((box[1, 0] - grid.x_left) / h - 0.5) + 1)
    if r0 >= r1 or c0 >= c1:
        return
    inside = _near_core(
        core,
        float(packing.rounding_radius[j]),
        grid.x(np.arange(c0, c1)),
        grid.y(np.arange(r0, r1)),
    )
    labels[r0:r1, c0:c1][inside] = j + 1


def _lines(box: FloatArray, grid: PixelGrid) -> tuple[IntArray, IntArray, FloatArray, FloatArray]:
    """Copy, line (``layer * n_rows + row``), y and z of every voxel line the 3D boxes cross."""
    r0, r1 = _row_span(box, grid)
    k0, k1 = _layer_span(box, grid)
    n_rows = np.maximum(r1 - r0, 0)
    n_lines = n_rows * np.maximum(k1 - k0, 0)
    copy = np.repeat(np.arange(box.shape[0]), n_lines)
    t = np.arange(copy.shape[0], dtype=np.int64) - np.repeat(np.cumsum(n_lines) - n_lines, n_lines)
    per_layer = n_rows[copy]
    row = r0[copy] + t % np.maximum(per_layer, 1)
    layer = k0[copy] + t // np.maximum(per_layer, 1)
    return copy, layer * grid.n_rows + row, grid.y(row), grid.z(layer)


def _fill_polyhedra(
    labels: NDArray[np.int32], grid: PixelGrid, packing: Packing, j: IntArray, shift: FloatArray
) -> None:
    """Scanline fill of the sharp convex polyhedra ``j`` (offset by ``shift``), line by line.

    A voxel centre ``p`` is in polyhedron ``j`` when ``n_f . (p - c) <= s_f``
    for all its faces ``f`` (``c`` its centre, ``n_f`` the outward normal,
    ``s_f`` the support); along a line of fixed y and z every face bounds x
    on one side, and the bounds give the run of voxels inside.
    """
    counts = packing.face_offsets[j + 1] - packing.face_offsets[j]
    width = int(counts.max())
    # pad every polyhedron to ``width`` faces by repeating its last one (the same half-space)
    face = packing.face_offsets[j, None] + np.minimum(np.arange(width), counts[:, None] - 1)
    normal = packing.normals[face]
    centre = packing.centre[j] + shift
    support = packing.support[face] + np.einsum("mfk,mk->mf", normal, centre)
    lo, hi = _bounds(packing, j)
    copy, line, y, z = _lines(np.stack([lo + shift, hi + shift], axis=1), grid)
    # inside face f: a x <= b with a = n_x and b = s + n . c - n_y y - n_z z
    a = normal[copy, :, 0]
    b = support[copy] - normal[copy, :, 1] * y[:, None] - normal[copy, :, 2] * z[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        bound = b / a
    xl = np.where(a < 0, bound, -np.inf).max(axis=1)
    xr = np.where(a > 0, bound, np.inf).min(axis=1)
    xl[~np.all((a != 0) | (b >= 0), axis=1)] = np.nan  # outside a face parallel to x
    _fill(labels, grid, line, xl, xr, (j + 1).astype(np.int32)[copy])


def _fill_spheres(
    labels: NDArray[np.int32], grid: PixelGrid, packing: Packing, j: IntArray, shift: FloatArray
) -> None:
    """Scanline fill of the spheres ``j``: one core point, grown by its rounding radius."""
    centre = packing.vertices[packing.offsets[j]] + packing.centre[j] + shift
    rho = packing.rounding_radius[j]
    copy, line, y, z = _lines(
        np.stack([centre - rho[:, None], centre + rho[:, None]], axis=1), grid
    )
    dy, dz = y - centre[copy, 1], z - centre[copy, 2]
    with np.errstate(invalid="ignore"):
        half = np.sqrt(rho[copy] ** 2 - dy * dy - dz * dz)  # NaN where the line misses it
    cx = centre[copy, 0]
    _fill(labels, grid, line, cx - half, cx + half, (j + 1).astype(np.int32)[copy])


def _draw_solids(labels: NDArray[np.int32], grid: PixelGrid, packing: Packing) -> None:
    """Give every voxel whose centre lies in placed solid ``j`` the label ``j + 1``.

    A solid is a sharp polyhedron (4 faces or more) or a sphere (no faces, a
    rounding radius), as a 3D packing's validation requires.
    """
    if packing.n_placed == 0:
        return
    j, shift, box = _copies(packing, grid)
    faces = packing.face_offsets[j + 1] - packing.face_offsets[j]
    rho = packing.rounding_radius[j]
    sharp = np.flatnonzero((rho <= 0) & (faces >= 4))
    spheres = np.flatnonzero((rho > 0) & (faces == 0))
    r0, r1 = _row_span(box, grid)
    k0, k1 = _layer_span(box, grid)
    cols = np.ceil((box[:, 1, 0] - box[:, 0, 0]) / grid.size).astype(np.int64) + 1
    work = np.maximum(r1 - r0, 0) * np.maximum(k1 - k0, 0) * (faces + cols)
    for part, fill in ((sharp, _fill_polyhedra), (spheres, _fill_spheres)):
        for s in _chunks(work[part]):
            fill(labels, grid, packing, j[part[s]], shift[part[s]])


def _draw(labels: NDArray[np.int32], grid: PixelGrid, packing: Packing) -> None:
    """Give every pixel whose centre lies in placed particle ``j`` the label ``j + 1``."""
    if packing.n_placed == 0:
        return
    j, shift, box = _copies(packing, grid)
    counts = packing.offsets[j + 1] - packing.offsets[j]
    rho = packing.rounding_radius[j]
    sharp = np.flatnonzero((rho <= 0) & (counts >= 3))  # sharp outlines of fewer corners: no area
    disks = np.flatnonzero((rho > 0) & (counts == 1))
    r0, r1 = _row_span(box, grid)
    cols = np.ceil((box[:, 1, 0] - box[:, 0, 0]) / grid.size) + 1
    work = np.maximum(r1 - r0, 0) * (counts + cols.astype(np.int64))
    for part, fill in ((sharp, _fill_polygons), (disks, _fill_disks)):
        for s in _chunks(work[part]):
            fill(labels, grid, packing, j[part[s]], shift[part[s]])
    for i in np.flatnonzero((rho > 0) & (counts > 1)).tolist():
        _fill_rounded(labels, grid, packing, int(j[i]), box[i], shift[i])


def _domain_mask(domain: Domain, grid: PixelGrid) -> BoolArray:
    """Mask of the pixels (voxels) whose centre lies inside ``domain``."""
    xs = grid.x(np.arange(grid.n_cols))
    ys = grid.y(np.arange(grid.n_rows))
    if isinstance(domain, Box):  # periodic: half-open [min, max) along every axis
        centres = (xs, ys, grid.z(np.arange(grid.n_layers)))
        b = domain.bounds()
        along = [
            (c >= b[2 * a]) & (c < b[2 * a + 1])
            if domain.periodic
            else (c > b[2 * a]) & (c < b[2 * a + 1])
            for a, c in enumerate(centres)
        ]
        out: BoolArray = along[2][:, None, None] & along[1][None, :, None] & along[0][None, None, :]
        return out
    if isinstance(domain, Cylinder):  # the voxels of every layer inside the circle
        zs = grid.z(np.arange(grid.n_layers))
        disk = np.hypot(xs[None, :] - domain.cx, ys[:, None] - domain.cy) < domain.radius
        height = (zs > domain.zmin) & (zs < domain.zmax)
        out = height[:, None, None] & disk[None, :, :]
        return out
    if isinstance(domain, PeriodicRectangle):  # half-open: [xmin, xmax) x [ymin, ymax)
        cols = (xs >= domain.xmin) & (xs < domain.xmax)
        rows = (ys >= domain.ymin) & (ys < domain.ymax)
        out = rows[:, None] & cols[None, :]
        return out
    if isinstance(domain, Rectangle):
        cols = (xs > domain.xmin) & (xs < domain.xmax)
        rows = (ys > domain.ymin) & (ys < domain.ymax)
        out = rows[:, None] & cols[None, :]
        return out
    out = np.empty(grid.shape, dtype=np.bool_)
    for r in range(0, grid.n_rows, _ROWS_PER_CHUNK):
        chunk = ys[r : r + _ROWS_PER_CHUNK]
        points = np.column_stack([np.tile(xs, chunk.shape[0]), np.repeat(chunk, xs.shape[0])])
        out[r : r + chunk.shape[0]] = domain.contains(points).reshape(chunk.shape[0], -1)
    return out


def rasterise(
    packing: Packing, pixel_size: float = 0.0, max_pixels: int = DEFAULT_MAX_PIXELS
) -> RasterImage:
    """Sample the placed particles of ``packing`` at the pixel (voxel) centres.

    A pixel centre on the outlines of two touching particles goes to one of them.

    Parameters
    ----------
    packing
        The packing: a 2D one gives pixels, a 3D one voxels.
    pixel_size, max_pixels
        See :func:`pixel_grid`.

    Raises
    ------
    ExportError
        One line, for a bad pixel size or an image larger than ``max_pixels``.
    """
    grid = pixel_grid(packing, pixel_size, max_pixels)
    labels = np.zeros(grid.shape, dtype=np.int32)
    (_draw_solids if grid.dimension == 3 else _draw)(labels, grid, packing)
    labels[~_domain_mask(packing.domain, grid)] = OUTSIDE_LABEL
    return RasterImage(grid, labels, packing.mineral.copy())


# ---------------------------------------------------------------------------
# files


def image_paths(path: Path) -> dict[str, Path]:
    """Files of an image export whose main file (the binary PNG) is ``path``.

    Examples
    --------
    >>> for p in image_paths(Path("out/packing.png")).values():
    ...     print(p.name)
    packing.png
    packing_labels.tif
    packing_minerals.png
    packing.npy
    packing_image.json
    """
    path = Path(path)
    return {
        "binary": path,
        "labels": path.with_name(f"{path.stem}_labels.tif"),
        "minerals": path.with_name(f"{path.stem}_minerals.png"),
        "phases": path.with_name(f"{path.stem}.npy"),
        "meta": path.with_name(f"{path.stem}_image.json"),
    }


def _write(path: Path, write: Any) -> None:
    """Write ``path`` atomically with ``write(file)``; one line on an OS error."""
    try:
        with _atomic_file(path) as fh:
            write(fh)
    except OSError as err:
        why = err.strerror or type(err).__name__
        raise ExportError(f"cannot write {path}: {why}") from err


def _save_png(path: Path, image: NDArray[np.uint8]) -> None:
    from PIL import Image

    picture = Image.fromarray(image)
    _write(path, lambda fh: picture.save(fh, format="PNG"))


def _save_tiff(path: Path, image: NDArray[np.int32]) -> None:
    """Write a 2D image as one TIFF page, a 3D one as one page per layer (layer 0 first)."""
    from PIL import Image, features

    pages = [
        Image.fromarray(np.ascontiguousarray(page, dtype=np.int32))
        for page in (image if image.ndim == 3 else image[None])
    ]
    options: dict[str, Any] = (
        {"compression": "tiff_adobe_deflate"} if features.check("libtiff") else {}
    )
    if len(pages) == 1:
        _write(path, lambda fh: pages[0].save(fh, format="TIFF", **options))
        return
    # Pillow reads back what it wrote of a multi-page TIFF: compose it in memory (compressed)
    buffer = io.BytesIO()
    pages[0].save(buffer, format="TIFF", save_all=True, append_images=pages[1:], **options)
    _write(path, lambda fh: fh.write(buffer.getbuffer()))


AXES = {
    2: ["row: y, from the top", "column: x, from the left"],
    3: ["layer: z, from the bottom", "row: y, from the top", "column: x, from the left"],
}
"""The ``axes`` of ``<stem>_image.json``: what the array indices run along, by dimension."""


def _metadata(packing: Packing, image: RasterImage, files: Mapping[str, Path]) -> dict[str, Any]:
    g = image.grid
    solid = float(packing.measure()[packing.placed].sum())
    layer = {}
    if g.dimension == 3:
        k = image.middle_layer
        layer = {"png_layer": k, "png_z": float(g.z(np.array(k)))}
    return {
        "format": IMAGE_FORMAT,
        "format_version": 1,
        "version": packing.version,
        "scene": packing.scene.get("name"),
        "seed": packing.seed,
        "pixel_size": g.size,
        "shape": list(g.shape),
        "axes": AXES[g.dimension],
        "extent": list(g.bounds()),
        **layer,
        "domain": packing.domain.to_dict(),
        "mineral_names": list(packing.mineral_names),
        "pixels_inside": int(np.count_nonzero(image.inside)),
        "pixels_solid": int(np.count_nonzero(image.solid)),
        "phi_image": image.phi,
        "phi_exact": solid / packing.domain.measure,
        "files": {key: p.name for key, p in files.items() if key != "meta"},
    }


class ImageExporter(Exporter[Packing]):
    """Binary, label and mineral images and a PoreSpy phase array (see :func:`image_paths`).

    ``<stem>.png`` is the binary image (8-bit grey: solid 255, void 0, outside
    the domain 128), ``<stem>_labels.tif`` the particle labels (int32: 0 void,
    ``j + 1`` particle ``j``, -1 outside), ``<stem>_minerals.png`` the minerals
    (8-bit: 0 void, ``k + 1`` mineral ``k``, 255 outside), ``<stem>.npy`` the
    phases in PoreSpy's convention (uint8: 1 pore, 0 solid, 2 outside) and
    ``<stem>_image.json`` the pixel size, extent and solid fractions.

    For a 3D packing the label TIFF has one page per layer (layer 0, the
    bottom, first) and the ``.npy`` array is ``(layers, rows, columns)``; the
    two PNG files show the middle layer (:attr:`RasterImage.middle_layer`).
    """

    suffix = ".png"

    def __init__(self, config: ImageConfig | None = None) -> None:
        self.config = config or ImageConfig()

    def companions(self, path: Path) -> tuple[Path, ...]:
        """Return the label TIFF, the minerals PNG, the ``.npy`` and the metadata file."""
        return tuple(p for key, p in image_paths(path).items() if key != "binary")

    def export(
        self, packing: Packing, path: Path, *, analyses: Mapping[str, Analyzer] | None = None
    ) -> Path:
        """Rasterise and write the five files; return the path of the binary PNG."""
        _check_minerals(len(packing.mineral_names))
        files = image_paths(Path(path))
        image = rasterise(packing, self.config.pixel_size, self.config.max_pixels)
        shown = image.layer(image.middle_layer) if image.grid.dimension == 3 else image
        _save_png(files["binary"], shown.binary())
        _save_tiff(files["labels"], image.labels)
        _save_png(files["minerals"], shown.minerals())
        phases = image.phases()
        _write(files["phases"], lambda fh: np.save(fh, phases, allow_pickle=False))
        meta = json.dumps(_finite_or_none(_metadata(packing, image, files)), indent=2)
        _write(files["meta"], lambda fh: fh.write((meta + "\n").encode("utf-8")))
        return files["binary"]


# ---------------------------------------------------------------------------
# registration


@hookimpl
def regopack_exporters() -> Iterable[ExporterSpec]:
    """Register the image exporter."""
    return [
        ExporterSpec(
            "image",
            ImageConfig,
            ImageExporter,
            "Binary, label and mineral images (PNG, TIFF, .npy) for pore studies; voxels in 3D.",
            dimensions=(2, 3),
        )
    ]

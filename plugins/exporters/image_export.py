"""Raster images of a packing for image-based pore studies (exporter ``image``).

The placed particles are sampled on a grid of square pixels: a pixel belongs
to a particle when its centre lies in the particle (on or inside a sharp
outline; within the rounding radius of the core of a rounded one, so disks
are exact). The grid covers the domain's bounding box from its top-left
corner; row 0 is the top of the domain (largest y), column 0 its left side
(smallest x). Pixels whose centre lies outside the domain (around a circle or
polygon, or past a side that the pixel size does not divide) have their own
value in every image and are neither solid nor pore. In a periodic domain a
particle that crosses a side is drawn on both sides.

>>> from regopack.testing import packing_from_polygons
>>> p = packing_from_polygons([[(1, 1), (3, 1), (3, 3), (1, 3)]], domain=(0, 4, 0, 4))
>>> image = rasterise(p, pixel_size=1.0)
>>> image.labels.tolist()
[[0, 0, 0, 0], [0, 1, 1, 0], [0, 1, 1, 0], [0, 0, 0, 0]]
>>> float(image.phi)
0.25
"""

from __future__ import annotations

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
from regopack.geometry.domain import Domain, PeriodicRectangle, Rectangle
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
"""Default largest image (pixels): about 16 000 × 16 000."""

MAX_PIXELS_LIMIT = 2**29
"""Largest ``max_pixels`` allowed (the label TIFF stays below the 4 GiB of a classic TIFF)."""

BYTES_PER_PIXEL = 10
"""Memory an export needs per pixel, roughly (labels, masks and one file's buffer)."""

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
"""Work (rows times corners plus bounding-box pixels) that one scanline fill handles at once."""


class ImageConfig(BaseModel):
    """Parameters of the image exporter."""

    model_config = ConfigDict(extra="forbid", strict=True)

    pixel_size: float = Field(
        0.0,
        ge=0,
        allow_inf_nan=False,
        description=(
            "Side of a square pixel in the length unit; 0 takes d_min/10 (d_min the smallest "
            "placed particle's equivalent diameter), made just small enough that a whole "
            "number of pixels spans the domain's width."
        ),
    )
    max_pixels: int = Field(
        DEFAULT_MAX_PIXELS,
        gt=0,
        le=MAX_PIXELS_LIMIT,
        description=(
            "Largest image, in pixels; a larger one is refused before anything is allocated "
            "(an export needs about 10 bytes of memory a pixel)."
        ),
    )


@dataclass(frozen=True)
class PixelGrid:
    """Square pixels over a domain's bounding box, row 0 at the top.

    The centre of pixel ``(row, col)`` is ``(x_left + (col + 0.5) size,
    y_top - (row + 0.5) size)``.
    """

    x_left: float
    y_top: float
    size: float
    n_rows: int
    n_cols: int

    @property
    def shape(self) -> tuple[int, int]:
        """``(n_rows, n_cols)``."""
        return (self.n_rows, self.n_cols)

    def x(self, cols: NDArray[Any]) -> FloatArray:
        """Return the x of the centres of the columns ``cols``."""
        out: FloatArray = self.x_left + (np.asarray(cols, dtype=np.float64) + 0.5) * self.size
        return out

    def y(self, rows: NDArray[Any]) -> FloatArray:
        """Return the y of the centres of the rows ``rows``."""
        out: FloatArray = self.y_top - (np.asarray(rows, dtype=np.float64) + 0.5) * self.size
        return out

    def extent(self) -> tuple[float, float, float, float]:
        """``(left, right, bottom, top)`` of the image (matplotlib's ``extent``)."""
        return (
            self.x_left,
            self.x_left + self.n_cols * self.size,
            self.y_top - self.n_rows * self.size,
            self.y_top,
        )


@dataclass(frozen=True)
class RasterImage:
    """A packing sampled on a :class:`PixelGrid`.

    Attributes
    ----------
    grid
        The pixels.
    labels
        ``(n_rows, n_cols)`` int32: 0 void, ``j + 1`` particle of draw index
        ``j``, :data:`OUTSIDE_LABEL` outside the domain.
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
    """Return the pixels of an image of ``packing``, checked against ``max_pixels``.

    Parameters
    ----------
    packing
        The packing (its domain and, for the default size, its particles).
    pixel_size
        Side of a pixel; 0 takes :func:`default_pixel_size`, reduced so that
        a whole number of pixels spans the domain's width.
    max_pixels
        Largest number of pixels allowed.

    Raises
    ------
    ExportError
        One line, when ``pixel_size`` is negative or not finite, or the image
        would have more than ``max_pixels`` pixels.
    """
    if not (math.isfinite(pixel_size) and pixel_size >= 0):
        raise ExportError(f"pixel_size = {pixel_size!r}: a pixel size is a finite number > 0")
    xmin, xmax, ymin, ymax = (float(v) for v in packing.domain.bounds())
    width, height = xmax - xmin, ymax - ymin
    size = float(pixel_size)
    if size == 0:
        size = width / _count(width, default_pixel_size(packing))
    n_cols, n_rows = _count(width, size), _count(height, size)
    total = n_cols * n_rows
    if total > max_pixels:
        smallest = math.sqrt(width * height / max_pixels)
        raise ExportError(
            f"pixel_size = {size:.6g} gives an image of {n_cols} x {n_rows} = {total} pixels, "
            f"more than max_pixels = {max_pixels} (about {BYTES_PER_PIXEL} bytes of memory a "
            f"pixel); use pixel_size >= {smallest:.3g} or raise max_pixels "
            f"(at most {MAX_PIXELS_LIMIT})"
        )
    return PixelGrid(xmin, ymax, size, n_rows, n_cols)


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
    """Lower-left and upper-right corners ``(n, 2)`` of the particles ``idx``, rounding included."""
    v, starts = packing.vertices, packing.offsets[:-1]
    lo = np.column_stack(
        [np.minimum.reduceat(v[:, 0], starts), np.minimum.reduceat(v[:, 1], starts)]
    )
    hi = np.column_stack(
        [np.maximum.reduceat(v[:, 0], starts), np.maximum.reduceat(v[:, 1], starts)]
    )
    grow = packing.rounding_radius[idx, None]
    return lo[idx] + packing.centre[idx] - grow, hi[idx] + packing.centre[idx] + grow


def _copies(packing: Packing, grid: PixelGrid) -> tuple[IntArray, FloatArray, FloatArray]:
    """Draw index, offset ``(n, 2)`` and shifted bounding box of every copy to draw.

    A walled domain has one copy per placed particle; in a periodic domain a
    particle that crosses a side has a copy shifted by a period for every
    side (and corner) of the image it reaches. Copies are in draw order.
    """
    idx = np.flatnonzero(packing.placed).astype(np.int64)
    lo, hi = _bounds(packing, idx)
    d = packing.domain
    if not isinstance(d, PeriodicRectangle):
        return idx, np.zeros((idx.shape[0], 2)), np.stack([lo, hi], axis=1)
    left, right, bottom, top = grid.extent()
    rows, shifts = [], []
    for sx in (-d.width, 0.0, d.width):
        for sy in (-d.height, 0.0, d.height):
            near = (hi[:, 0] + sx >= left) & (lo[:, 0] + sx <= right)
            near &= (hi[:, 1] + sy >= bottom) & (lo[:, 1] + sy <= top)
            rows.append(np.flatnonzero(near))
            shifts.append(np.tile([sx, sy], (rows[-1].shape[0], 1)))
    at = np.concatenate(rows)
    order = np.argsort(at, kind="stable")
    at, shift = at[order], np.concatenate(shifts)[order]
    return idx[at], shift, np.stack([lo[at] + shift, hi[at] + shift], axis=1)


def _row_span(box: FloatArray, grid: PixelGrid) -> tuple[IntArray, IntArray]:
    """Rows ``[r0, r1)`` whose centres may lie within the boxes' y range."""
    h = grid.size
    r0 = np.ceil((grid.y_top - box[:, 1, 1]) / h - 0.5)
    r1 = np.floor((grid.y_top - box[:, 0, 1]) / h - 0.5) + 1
    return (
        np.clip(r0, 0, grid.n_rows).astype(np.int64),
        np.clip(r1, 0, grid.n_rows).astype(np.int64),
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
    """Set the pixels of every row ``rows[i]`` whose centre x lies in ``[xl[i], xr[i]]``."""
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
    """Mask of the pixels whose centre lies inside ``domain``."""
    xs = grid.x(np.arange(grid.n_cols))
    ys = grid.y(np.arange(grid.n_rows))
    if isinstance(domain, PeriodicRectangle):  # half-open: [xmin, xmax) x [ymin, ymax)
        cols = (xs >= domain.xmin) & (xs < domain.xmax)
        rows = (ys >= domain.ymin) & (ys < domain.ymax)
        out: BoolArray = rows[:, None] & cols[None, :]
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
    """Sample the placed particles of ``packing`` at the pixel centres.

    A pixel centre on the outlines of two touching particles goes to one of them.

    Parameters
    ----------
    packing
        The packing.
    pixel_size, max_pixels
        See :func:`pixel_grid`.

    Raises
    ------
    ExportError
        One line, for a bad pixel size or an image larger than ``max_pixels``.
    """
    grid = pixel_grid(packing, pixel_size, max_pixels)
    labels = np.zeros(grid.shape, dtype=np.int32)
    _draw(labels, grid, packing)
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
    from PIL import Image, features

    picture = Image.fromarray(np.ascontiguousarray(image, dtype=np.int32))
    options = {"compression": "tiff_adobe_deflate"} if features.check("libtiff") else {}
    _write(path, lambda fh: picture.save(fh, format="TIFF", **options))


def _metadata(packing: Packing, image: RasterImage, files: Mapping[str, Path]) -> dict[str, Any]:
    g = image.grid
    area = packing.area()[packing.placed].sum()
    return {
        "format": IMAGE_FORMAT,
        "format_version": 1,
        "version": packing.version,
        "scene": packing.scene.get("name"),
        "seed": packing.seed,
        "pixel_size": g.size,
        "shape": [g.n_rows, g.n_cols],
        "extent": list(g.extent()),
        "domain": packing.domain.to_dict(),
        "mineral_names": list(packing.mineral_names),
        "pixels_inside": int(np.count_nonzero(image.inside)),
        "pixels_solid": int(np.count_nonzero(image.solid)),
        "phi_image": image.phi,
        "phi_exact": float(area) / packing.domain.area,
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
        _save_png(files["binary"], image.binary())
        _save_tiff(files["labels"], image.labels)
        _save_png(files["minerals"], image.minerals())
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
            "Binary, label and mineral images (PNG, TIFF, .npy) for pore studies.",
        )
    ]

"""The tiles of a packing: a grid over the floor, coloured so that equal colours never touch.

The floor of a domain (``x`` in the plane, ``x`` and ``y`` in space; the
vertical axis is the last) is cut into equal tiles of about the scene's
``tiles.side``. A tile's *window* is the part of the floor its particles'
centres may take (every height). Tiles are coloured by the parity of their
position along each floor axis (two colours in the plane, four in space), so
that two tiles of one colour are at least one tile apart along some axis:
packed at the same time, their particles cannot meet when a tile is wider
than any two particles' circumradii. The colours are the phases of the
schedule: a tile packs against the tiles of earlier colours, which are
done.

Examples
--------
>>> import numpy as np
>>> lay = tile_layout(np.array([0.0, 0.0, 0.0]), np.array([40.0, 40.0, 10.0]), 3, False, 20.0)
>>> [t.colour for t in lay.tiles]
[0, 2, 1, 3]
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

MAX_TILES = 1 << 20
"""Most tiles of one packing."""


@dataclass(frozen=True)
class Tile:
    """One tile: its index, position on the floor grid, colour and centre window."""

    index: int
    cell: tuple[int, ...]
    colour: int
    lo: FloatArray
    """Lower corner of the centre window (``dimension`` values; the vertical one the domain's)."""
    hi: FloatArray
    """Upper corner of the centre window."""


@dataclass(frozen=True)
class TileLayout:
    """The tiles of a domain's floor grid.

    Attributes
    ----------
    lo, hi
        The domain's bounding box corners.
    counts
        Tiles along each floor axis.
    periodic
        Whether the floor axes wrap around (a periodic domain).
    tiles
        Every tile, in grid order (the last floor axis fastest).
    """

    lo: FloatArray
    hi: FloatArray
    counts: tuple[int, ...]
    periodic: bool
    tiles: tuple[Tile, ...]

    @property
    def floor_axes(self) -> int:
        """Number of floor axes (the dimension less one)."""
        return len(self.counts)

    @property
    def colours(self) -> int:
        """Number of colours, the phases of the schedule."""
        return 1 << self.floor_axes

    def share(self, tile: Tile) -> float:
        """Return the tile's share of the domain's floor (the windows tile it exactly)."""
        span = self.hi[: self.floor_axes] - self.lo[: self.floor_axes]
        width = tile.hi[: self.floor_axes] - tile.lo[: self.floor_axes]
        return float(np.prod(width / span))

    def owner(self, points: FloatArray) -> NDArray[np.int64]:
        """Index of the tile whose window holds each point's floor position.

        Along a periodic axis the position wraps into the domain; along a
        walled one it is clamped to the first or last tile.
        """
        cells = np.zeros(points.shape[0], dtype=np.int64)
        for a, n in enumerate(self.counts):
            span = float(self.hi[a] - self.lo[a])
            rel = (points[:, a] - self.lo[a]) / span
            if self.periodic:
                rel = np.mod(rel, 1.0)
            c = np.clip(np.floor(rel * n).astype(np.int64), 0, n - 1)
            cells = cells * n + c
        return cells

    def grown(self, tile: Tile, margin: float) -> Tile:
        """Return the tile with its window grown by ``margin`` along the floor, but at walls."""
        lo = tile.lo.copy()
        hi = tile.hi.copy()
        for a in range(self.floor_axes):
            if self.periodic or tile.cell[a] > 0:
                lo[a] -= margin
            if self.periodic or tile.cell[a] < self.counts[a] - 1:
                hi[a] += margin
        return Tile(tile.index, tile.cell, tile.colour, lo, hi)

    def phase(self, colour: int) -> list[Tile]:
        """Return the tiles of one colour, in index order."""
        return [t for t in self.tiles if t.colour == colour]

    def floor_gap(self, tile: Tile, points: FloatArray) -> FloatArray:
        """Distance along the floor from each point to the tile's window (0 inside it).

        Along a periodic axis the distance is to the nearest image of the window.
        """
        gap2 = np.zeros(points.shape[0])
        for a in range(self.floor_axes):
            x = points[:, a]
            lo, hi = float(tile.lo[a]), float(tile.hi[a])
            if self.periodic:
                period = float(self.hi[a] - self.lo[a])
                mid = 0.5 * (lo + hi)
                x = mid + np.mod(x - mid + 0.5 * period, period) - 0.5 * period
            d = np.maximum(np.maximum(lo - x, x - hi), 0.0)
            gap2 += d * d
        out: FloatArray = np.sqrt(gap2)
        return out


def tile_counts(span: FloatArray, side: float | Sequence[float], periodic: bool) -> tuple[int, ...]:
    """Tiles along each floor axis: about ``side`` wide, an even count along a periodic axis.

    An even count keeps the colours alternating across the periodic seam; a
    periodic axis of fewer than two tiles' width has one tile (no seam to
    alternate across). Returns ``(1, ...)`` where a single tile covers an axis.
    """
    sides = [float(side)] * len(span) if isinstance(side, int | float) else list(side)
    out = []
    for s, width in zip(span, sides, strict=True):
        n = max(1, math.floor(float(s) / width + 0.5))
        if periodic and n > 1 and n % 2:
            n = n - 1 if n > 2 else 2
        out.append(n)
    return tuple(out)


def tile_layout(
    lo: FloatArray,
    hi: FloatArray,
    dimension: int,
    periodic: bool,
    side: float | Sequence[float],
) -> TileLayout:
    """Cut the floor of the box ``[lo, hi]`` into tiles of about ``side`` (or one per axis).

    Raises
    ------
    ValueError
        When a side is not a positive finite length, there is not one side per
        floor axis, or the grid would hold more than :data:`MAX_TILES` tiles.
    """
    sides = [float(side)] * (dimension - 1) if isinstance(side, int | float) else list(side)
    if len(sides) != dimension - 1:
        raise ValueError(
            f"give one side, or one per floor axis ({dimension - 1}), not {len(sides)}"
        )
    if not all(math.isfinite(v) and v > 0 for v in sides):
        raise ValueError(f"the tiles' side must be a positive length, not {side!r}")
    lo = np.asarray(lo, dtype=np.float64)
    hi = np.asarray(hi, dtype=np.float64)
    floor = dimension - 1
    span = hi[:floor] - lo[:floor]
    counts = tile_counts(span, sides, periodic)
    if math.prod(counts) > MAX_TILES:
        raise ValueError(f"{math.prod(counts)} tiles: more than {MAX_TILES}; give a larger side")
    width = span / np.array(counts, dtype=np.float64)
    tiles = []
    for index, cell in enumerate(itertools.product(*(range(n) for n in counts))):
        t_lo = lo.copy()
        t_hi = hi.copy()
        for a, c in enumerate(cell):
            t_lo[a] = lo[a] + c * width[a]
            # the last tile ends exactly on the domain's side (no rounding gap)
            t_hi[a] = hi[a] if c == counts[a] - 1 else lo[a] + (c + 1) * width[a]
        colour = sum((c % 2) << a for a, c in enumerate(cell))
        tiles.append(Tile(index, tuple(cell), colour, t_lo, t_hi))
    return TileLayout(lo, hi, counts, periodic, tuple(tiles))

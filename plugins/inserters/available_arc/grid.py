"""Uniform cell grid over the domain for neighbour queries.

Every inserted particle is registered in all cells its bounding disk of
radius ``reach`` overlaps; a query lists each particle of the cells a box
overlaps once (a per-query stamp removes repeats).
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

import regopack.base.jit  # noqa: F401  (sets the kernel cache folder before numba compiles)

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def grid_layout(bounds: FloatArray, reach: FloatArray) -> tuple[float, int, int, int]:
    """Choose the cell size and size the registration store.

    Parameters
    ----------
    bounds
        ``[xmin, xmax, ymin, ymax]`` of the domain.
    reach
        Registration radius of every particle.

    Returns
    -------
    cell, nx, ny, capacity
        Cell size, cells along x and y, and an upper bound on registrations.
    """
    width = float(bounds[1] - bounds[0])
    height = float(bounds[3] - bounds[2])
    n = max(int(reach.shape[0]), 1)
    typical = float(np.median(reach)) if reach.shape[0] else max(width, height)
    cell = max(3.0 * typical, math.sqrt(width * height / (4.0 * n)), 1e-300)
    cell = min(cell, max(width, height)) if max(width, height) > 0 else 1.0
    nx = max(1, math.ceil(width / cell))
    ny = max(1, math.ceil(height / cell))
    # one cell of slack per axis: a disk edge on a cell boundary may round either way
    per_x = np.minimum(np.floor(2.0 * reach / cell) + 3.0, float(nx))
    per_y = np.minimum(np.floor(2.0 * reach / cell) + 3.0, float(ny))
    capacity = int(np.sum(per_x * per_y)) + 1
    return cell, nx, ny, capacity


def empty_grid(n: int, cells: int, capacity: int) -> dict[str, NDArray[Any]]:
    """Arrays of an empty grid, by the field names of the state tuples that hold them.

    ``head`` (per cell: its last registration, -1 for none), ``nxt`` and
    ``item`` (``capacity`` registrations, filled by :func:`grid_insert`) and
    ``stamp`` (per particle, marks the particles a query has listed) for
    ``n`` particles and ``cells`` cells.
    """
    return {
        "head": np.full(cells, -1, dtype=np.int64),
        "nxt": np.empty(capacity, dtype=np.int64),
        "item": np.empty(capacity, dtype=np.int64),
        "stamp": np.zeros(n, dtype=np.int64),
    }


@numba.njit(cache=True)
def cell_range(lo: float, hi: float, origin: float, cell: float, count: int) -> tuple[int, int]:
    """Inclusive index range of the cells that ``[lo, hi]`` overlaps along one axis.

    Indices are clamped to the grid, so an interval beyond one side maps to
    the cells on that side (registrations are clamped the same way).
    """
    a = math.floor((lo - origin) / cell)
    b = math.floor((hi - origin) / cell)
    a = min(max(a, 0), count - 1)
    b = min(max(b, 0), count - 1)
    return int(a), int(b)


@numba.njit(cache=True)
def grid_insert(
    p: int,
    x: float,
    y: float,
    reach: float,
    gpar: FloatArray,
    gdim: IntArray,
    head: IntArray,
    nxt: IntArray,
    item: IntArray,
) -> None:
    """Register particle ``p`` at ``(x, y)`` in every cell its disk of radius ``reach`` overlaps.

    ``gpar`` is ``[x0, y0, cell]``; ``gdim`` is ``[nx, ny, used]`` and ``used`` is updated.
    """
    x0, y0, cell = gpar[0], gpar[1], gpar[2]
    nx, ny = gdim[0], gdim[1]
    ia, ib = cell_range(x - reach, x + reach, x0, cell, nx)
    ja, jb = cell_range(y - reach, y + reach, y0, cell, ny)
    used = gdim[2]
    for j in range(ja, jb + 1):
        for i in range(ia, ib + 1):
            c = j * nx + i
            item[used] = p
            nxt[used] = head[c]
            head[c] = used
            used += 1
    gdim[2] = used

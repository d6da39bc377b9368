"""The uniform cell grid that the available-arc and rsa inserters register particles in."""

from __future__ import annotations

import numpy as np

from regopack.plugins.inserters.available_arc.grid import (
    cell_range,
    empty_grid,
    grid_insert,
    grid_layout,
)


def _listed(cell: int, head: np.ndarray, nxt: np.ndarray, item: np.ndarray) -> list[int]:
    out, e = [], head[cell]
    while e >= 0:
        out.append(int(item[e]))
        e = nxt[e]
    return out


def test_an_empty_grid_lists_nothing_and_takes_its_capacity_of_registrations() -> None:
    grid = empty_grid(5, 12, 40)
    assert sorted(grid) == ["head", "item", "nxt", "stamp"]
    assert grid["head"].shape == (12,) and np.all(grid["head"] == -1)
    assert grid["nxt"].shape == grid["item"].shape == (40,)
    assert grid["stamp"].shape == (5,) and np.all(grid["stamp"] == 0)
    assert all(a.dtype == np.int64 for a in grid.values())


def test_a_particle_is_registered_in_every_cell_its_disk_overlaps() -> None:
    bounds = np.array([0.0, 10.0, 0.0, 10.0])
    reach = np.array([1.0, 1.0, 1.0])
    cell, nx, ny, capacity = grid_layout(bounds, reach)
    grid = empty_grid(3, nx * ny, capacity)
    gpar = np.array([0.0, 0.0, cell])
    gdim = np.array([nx, ny, 0])
    grid_insert(0, 5.0, 5.0, 1.0, gpar, gdim, grid["head"], grid["nxt"], grid["item"])
    grid_insert(1, 0.0, 9.9, 1.0, gpar, gdim, grid["head"], grid["nxt"], grid["item"])
    ia, ib = cell_range(4.0, 6.0, 0.0, cell, nx)
    ja, jb = cell_range(4.0, 6.0, 0.0, cell, ny)
    used = (ib - ia + 1) * (jb - ja + 1)
    for j in range(ny):
        for i in range(nx):
            inside = ia <= i <= ib and ja <= j <= jb
            assert (0 in _listed(j * nx + i, grid["head"], grid["nxt"], grid["item"])) == inside
    # beyond a side, a disk is clamped to that side's cells
    assert cell_range(-5.0, -1.0, 0.0, cell, nx) == (0, 0)
    assert 1 in _listed((ny - 1) * nx, grid["head"], grid["nxt"], grid["item"])
    assert gdim[2] > used

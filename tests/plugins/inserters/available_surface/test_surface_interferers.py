"""The interferers of a candidate, gathered from the grid, against a plain search of all."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from regopack.plugins.inserters.available_surface.analysis import (
    Bounds,
    Placed,
    _interferers,
    grid_add,
    grid_for,
)


def _placed(seed: int, n: int, side: float, periodic: bool) -> tuple[object, Placed, Bounds]:
    """``n`` particles at random in a cube of ``side``, one large among many small ones."""
    rng = np.random.default_rng(seed)
    lo, hi = np.zeros(3), np.full(3, side)
    centre = rng.uniform(0.0, side, (n, 3))
    circum = rng.uniform(0.05, 0.2, n)
    circum[0] = 1.5  # the reach of every search spans the whole box's cells
    grid = grid_for(lo, hi, 2.0 * float(circum.max()), n)
    order = rng.permutation(n)
    for j in order:
        grid_add(grid, int(j), centre[j])
    placed = Placed(order, centre, circum, float(circum.max()))
    period = hi - lo if periodic else np.zeros(0)
    return grid, placed, Bounds(period, lo, hi, lo, hi)


def _plainly(placed: Placed, bounds: Bounds, pk: int, i: int, margin: float) -> set:
    """Every particle (or periodic image, up to two periods away) within the reach of ``pk``."""
    _, centre, circum, _ = placed
    shifts = [np.zeros(3)]
    if bounds.period.shape[0]:
        steps = itertools.product(range(-2, 3), repeat=3)  # reaches above a period
        shifts = [np.array(s, dtype=float) * bounds.period for s in steps]
    found = set()
    for j in range(centre.shape[0]):
        for shift in shifts:
            d = float(np.linalg.norm(centre[j] + shift - centre[pk]))
            if j == pk and d == 0.0:
                continue
            if d < circum[pk] + circum[j] + 2.0 * circum[i] + margin:
                found.add((j, *np.round(centre[j] + shift, 9)))
    return found


@pytest.mark.parametrize("periodic", [False, True])
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_grid_gathers_every_interferer_once_and_in_cell_order(
    seed: int, periodic: bool
) -> None:
    # hundreds of interferers: the gather outgrows its first arrays and gathers again
    grid, placed, bounds = _placed(seed, 600, 4.0, periodic)
    many = 0
    for pk, i, margin in [(0, 1, 0.0), (5, 0, 0.0), (7, 3, 0.3), (0, 0, 0.1)]:
        count, near, at = _interferers(grid, pk, i, placed, bounds, margin)
        got = [(int(near[m]), *np.round(at[m], 9)) for m in range(count)]
        assert len(got) == len(set(got))
        assert set(got) == _plainly(placed, bounds, pk, i, margin)
        many = max(many, count)
        if not periodic:
            # in the grid's order: cell by cell, each cell's in insertion order (the
            # analysis's caps and its random numbers follow it)
            cells = np.floor(placed.centre / grid.cell[0]).astype(np.int64) - grid.origin
            cells = np.minimum(np.maximum(cells, 0), grid.dims - 1)
            flat = (cells[:, 0] * grid.dims[1] + cells[:, 1]) * grid.dims[2] + cells[:, 2]
            rank = np.argsort(placed.order)
            listed = [int(j) for j in near[:count]]
            assert listed == sorted(listed, key=lambda j: (flat[j], rank[j]))
    assert many > 4 * 64  # beyond the first arrays' length

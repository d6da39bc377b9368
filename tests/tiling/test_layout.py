"""The tiles of a packing: windows that tile the floor, colours that never touch."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from regopack.tiling.layout import tile_counts, tile_layout
from regopack.tiling.run import split_count


@pytest.mark.parametrize("periodic", [False, True])
@pytest.mark.parametrize("dimension", [2, 3])
def test_the_windows_tile_the_floor_and_equal_colours_never_touch(
    periodic: bool, dimension: int
) -> None:
    lo = np.array([-31.0, 2.0, -5.0][:dimension])
    hi = np.array([49.0, 62.0, 7.0][:dimension])
    lay = tile_layout(lo, hi, dimension, periodic, 11.0)
    floor = dimension - 1
    assert lay.colours == 2**floor
    assert sum(lay.share(t) for t in lay.tiles) == pytest.approx(1.0, rel=1e-12)
    for t in lay.tiles:
        assert np.all(t.lo[floor:] == lo[floor:]) and np.all(t.hi[floor:] == hi[floor:])
        assert np.all(t.hi[:floor] > t.lo[:floor])
    # the windows meet exactly: each tile ends where the next along the axis starts
    for a in range(floor):
        edges = sorted({float(t.lo[a]) for t in lay.tiles} | {float(t.hi[a]) for t in lay.tiles})
        assert edges[0] == lo[a] and edges[-1] == hi[a]
        assert len(edges) == lay.counts[a] + 1
    if periodic:
        assert all(n % 2 == 0 or n == 1 for n in lay.counts)
    # two tiles of one colour are a whole tile apart along some floor axis (periodic too)
    width = min(float(np.min(t.hi[:floor] - t.lo[:floor])) for t in lay.tiles)
    for a, b in itertools.combinations(lay.tiles, 2):
        if a.colour != b.colour:
            continue
        gaps = []
        for ax in range(floor):
            shifts = [0.0]
            if periodic:
                period = float(hi[ax] - lo[ax])
                shifts = [-period, 0.0, period]
            gaps.append(
                min(max(0.0, b.lo[ax] + s - a.hi[ax], a.lo[ax] - b.hi[ax] - s) for s in shifts)
            )
        assert max(gaps) >= width * (1 - 1e-12)


def test_tile_counts_are_even_along_a_periodic_axis() -> None:
    assert tile_counts(np.array([100.0]), 20.0, True) == (4,)
    assert tile_counts(np.array([100.0]), 20.0, False) == (5,)
    assert tile_counts(np.array([30.0]), 20.0, True) == (2,)
    assert tile_counts(np.array([10.0]), 20.0, True) == (1,)


def test_a_periodic_floor_gap_takes_the_nearest_image() -> None:
    lay = tile_layout(np.zeros(2), np.array([100.0, 10.0]), 2, True, 25.0)
    first = lay.tiles[0]
    assert (float(first.lo[0]), float(first.hi[0])) == (0.0, 25.0)
    gap = lay.floor_gap(first, np.array([[99.0, 5.0], [30.0, 5.0], [10.0, 5.0]]))
    assert gap.tolist() == pytest.approx([1.0, 5.0, 0.0])


def test_bad_sides_are_refused() -> None:
    with pytest.raises(ValueError, match="positive"):
        tile_layout(np.zeros(3), np.ones(3), 3, False, 0.0)
    with pytest.raises(ValueError, match="more than"):
        tile_layout(np.zeros(3), np.full(3, 1e6), 3, False, 1.0)


@pytest.mark.parametrize("n", [0, 1, 7, 1000, 12345])
def test_split_count_gives_every_particle_to_one_tile(n: int) -> None:
    shares = np.array([0.1, 0.2, 0.3, 0.15, 0.25])
    parts = split_count(n, shares.tolist())
    assert sum(parts) == n
    assert np.all(np.abs(np.array(parts) - shares * n) < 1.0)


def test_a_side_per_axis_cuts_strips() -> None:
    lay = tile_layout(np.zeros(3), np.array([120.0, 120.0, 50.0]), 3, False, [30.0, 120.0])
    assert lay.counts == (4, 1)
    assert sorted({t.colour for t in lay.tiles}) == [0, 1]
    assert [len(lay.phase(c)) for c in range(4)] == [2, 2, 0, 0]
    with pytest.raises(ValueError, match="one per floor axis"):
        tile_layout(np.zeros(3), np.ones(3), 3, False, [1.0])


def test_owner_and_grown_windows() -> None:
    lay = tile_layout(np.zeros(3), np.array([40.0, 20.0, 10.0]), 3, False, 10.0)
    assert lay.counts == (4, 2)
    owner = lay.owner(np.array([[1.0, 1.0, 5.0], [39.0, 19.0, 5.0], [15.0, 12.0, 0.0]]))
    assert owner.tolist() == [0, 7, 3]
    corner = lay.grown(lay.tiles[0], 2.0)  # at the walls: grown inwards only
    assert corner.lo[:2].tolist() == [0.0, 0.0] and corner.hi[:2].tolist() == [12.0, 12.0]
    inner = lay.grown(lay.tiles[3], 2.0)
    assert inner.lo[:2].tolist() == [8.0, 8.0] and inner.hi[:2].tolist() == [22.0, 20.0]
    wrapped = tile_layout(np.zeros(3), np.array([40.0, 20.0, 10.0]), 3, True, 10.0)
    assert wrapped.owner(np.array([[-1.0, 21.0, 0.0]])).tolist() == [6]

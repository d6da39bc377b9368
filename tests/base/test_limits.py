"""Sizes derived from a scene are bounded before anything is allocated (regopack.base.limits)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from regopack.base.limits import LimitError, check_memory, derived_count, histogram_bins
from regopack.plugins.inserters.available_surface.analysis import MAX_GRID_CELLS, grid_for


@pytest.mark.parametrize("value", [math.inf, math.nan, -1.0, 1e300])
def test_a_derived_count_beyond_the_bound_is_refused(value: float) -> None:
    with pytest.raises(LimitError) as info:
        derived_count(value, "bins", 100, field="insertion.zone", given=5.0)
    assert str(info.value).startswith("insertion.zone = 5.0: gives ")
    assert info.value.located("--set").startswith("--set: insertion.zone = 5.0: ")


def test_memory_beyond_the_limit_is_refused_without_allocating() -> None:
    with pytest.raises(LimitError, match=r"need about 1\.0 TiB of memory; .* is 1\.0 GiB"):
        check_memory(2.0**40, "lots", field="count", given=7, limit=(2**30, "memory"))
    check_memory(2.0**20, "little", field="count", limit=(2**30, "memory"))


def test_a_grid_of_no_finite_size_never_reaches_a_kernel() -> None:
    lo, hi = np.array([-75.0, -5e299, -75.0]), np.array([75.0, 5e299, 75.0])
    with pytest.raises(LimitError, match=r"5e\+301 cells of the neighbour grid"):
        grid_for(lo, hi, 8.0, 30)
    side = float(round(MAX_GRID_CELLS ** (1 / 3))) * 8.0 * 2
    with pytest.raises(LimitError, match="cells of the neighbour grid"):
        grid_for(np.zeros(3), np.full(3, side), 8.0, 30)
    grid = grid_for(np.full(3, -75.0), np.full(3, 75.0), 8.0, 30)
    assert grid.head.shape == (int(np.prod(grid.dims)),)


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_bounds_are_ratios_of_lengths(scale: float) -> None:
    lo, hi = np.full(3, -75.0) * scale, np.full(3, 75.0) * scale
    assert grid_for(lo, hi, 8.0 * scale, 30).dims.tolist() == [20, 20, 20]


@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e6])
def test_histogram_bins_are_a_ratio_of_range_and_width(scale: float) -> None:
    assert (
        histogram_bins(0.0, 10.0 * scale, 0.1 * scale, field="near_bin", range_name="near") == 100
    )
    assert histogram_bins(0.0, 1.0 * scale, 5.0 * scale, field="near_bin", range_name="near") == 1
    with pytest.raises(LimitError, match=r"^near_bin = .*: gives 1e\+10 bins over near = "):
        histogram_bins(0.0, 10.0 * scale, 1e-9 * scale, field="near_bin", range_name="near")
    with pytest.raises(LimitError, match=r"^near_bin = inf: must be a finite number > 0$"):
        histogram_bins(0.0, 10.0 * scale, math.inf, field="near_bin", range_name="near")

"""A tile of the 3D sweep: obstacles filed as the front reaches them, centres in the window."""

from __future__ import annotations

import numpy as np

from regopack.geometry.solids import SolidBatch
from regopack.plugins.inserters.available_surface.state import SurfaceState
from regopack.plugins.inserters.available_surface.sweep import ACTIVE, SurfaceSweep


def _state(heights: list[float], window: tuple[np.ndarray, np.ndarray] | None = None):
    """Obstacles (radius 0.5) at x = y = 1 and the given heights, then 20 own spheres."""
    m = len(heights)
    radius = np.full(m + 20, 0.5)
    lo, hi = np.array([0.0, 0.0, 0.0]), np.array([8.0, 8.0, 40.0])
    st = SurfaceState(SolidBatch.of_spheres(radius), radius, lo, hi, window=window)
    for j, z in enumerate(heights):
        st.insert(j, np.array([1.0, 1.0, z]))
    return st


def test_obstacles_join_the_candidates_as_the_zone_rises_to_them() -> None:
    st = _state([0.5, 0.5, 10.0, 20.0, 30.0])
    sw = SurfaceSweep(st, 0.999, 4.0, "paced")
    sw.seed_with(5)
    z = sw.zones[0]
    assert sw.started and z.seeded
    assert z.members[: z.size].tolist() == [0, 1]  # the lowest bin only
    assert all(sw.flag[k] == ACTIVE for k in (0, 1))
    bins = [sw._bin_of(float(st.centre[k, 2])) for k in range(5)]
    raises = 0
    while sw._raise(z):
        raises += 1
        # an obstacle is a candidate exactly when the zone's top has reached its bin
        assert sorted(z.members[: z.size].tolist()) == [k for k in range(5) if bins[k] <= z.hi]
    assert raises > 0 and z.members[: z.size].tolist() == [0, 1, 2, 3, 4]


def test_a_tile_without_obstacles_starts_as_a_sweep_does() -> None:
    st = _state([])
    sw = SurfaceSweep(st, 0.999, 4.0, "paced")
    sw.seed_with(0)
    assert not sw.started
    assert all(not z.seeded for z in sw.zones)


def test_the_window_bounds_every_centre_besides_the_walls() -> None:
    window = (np.array([2.0, -np.inf, -np.inf]), np.array([5.0, np.inf, np.inf]))
    st = _state([0.5], window)
    assert st.begin(3)
    assert st.adm_lo.tolist() == [2.0, 0.5, 0.5]
    assert st.adm_hi.tolist() == [5.0, 7.5, 39.5]
    assert st.fits_at(np.array([4.0, 4.0, 4.0]))
    assert not st.fits_at(np.array([5.5, 4.0, 4.0]))

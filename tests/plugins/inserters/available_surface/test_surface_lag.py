"""The 3D sweep's lags: small particles offered after the front has risen by their depth."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import regopack
from regopack.geometry.solids import SolidBatch
from regopack.packing.core import Packing
from regopack.plugins.inserters.available_surface.state import SurfaceState
from regopack.plugins.inserters.available_surface.sweep import (
    STATUS_NOT_OFFERED,
    STATUS_PLACED,
    STATUS_REFUSED,
    SurfaceSweep,
)
from regopack.verification.polyhedra import verify_polyhedra


def scene(**insertion: Any) -> dict[str, Any]:
    """Spheres of 1-4 in a box 16 wide and 44 high, a zone of 16: the pilot runs."""
    return {
        "name": "lag3d",
        "seed": 2,
        "count": "auto",
        "domain": {"kind": "box", "width": 16.0, "height": 44.0, "depth": 16.0},
        "size": {"kind": "uniform", "d_min": 1.0, "d_max": 4.0},
        "phases": [{"name": "a", "fraction": 1.0, "shape": {"kind": "sphere"}}],
        "insertion": {
            "kind": "available-surface",
            "order": "sweep",
            "zone": 16.0,
            "lag": "pilot",
            **insertion,
        },
        "density": {"kind": "eta"},
    }


def _pack(data: dict[str, Any]) -> Packing:
    return regopack.pack(data, verify=False)


@pytest.fixture(scope="module")
def lagged() -> Packing:
    return _pack(scene(closing="tail"))


def test_the_pilot_learns_lags_for_the_fine_spheres(lagged: Packing) -> None:
    s = lagged.stats
    assert s["lag_pilot_particles"] > 0 and s["lag_samples"] > 20
    assert 0 < s["lagged"] < lagged.n_particles
    assert 0.0 < s["lag_max"] < 2.0 * s["zone"]
    assert s["pilot_time_s"] >= 0.0


def test_a_lagged_sweep_is_overlap_free_inside_the_box_and_reproducible(lagged: Packing) -> None:
    report = regopack.verify(lagged)
    assert report.ok, str(report)
    again = _pack(scene(closing="tail"))
    assert np.array_equal(lagged.centre, again.centre, equal_nan=True)
    assert np.array_equal(lagged.insertion_index, again.insertion_index)


def test_a_box_lower_than_the_pilot_needs_gets_no_lags() -> None:
    data = scene()
    data["domain"] = {"kind": "box", "width": 16.0, "height": 36.0, "depth": 16.0}  # < 2.5 zones
    a = _pack(data)
    assert a.stats["lagged"] == 0 and a.stats["lag_samples"] == 0
    data["insertion"]["lag"] = "none"
    b = _pack(data)
    assert "lagged" not in b.stats
    assert np.array_equal(a.centre, b.centre, equal_nan=True)


def test_lags_that_come_out_zero_leave_the_packing_as_without_them() -> None:
    """Equal spheres land at the front: no lag; the pilot's generator is its own."""
    runs = {}
    for mode in ("pilot", "none"):
        data = scene(lag=mode, zone=0.0)  # 6.06: three diameters
        data["size"] = {"kind": "uniform", "d_min": 2.0, "d_max": 2.02}
        data["domain"] = {"kind": "box", "width": 10.0, "height": 30.0, "depth": 10.0}
        runs[mode] = _pack(data)
    assert runs["pilot"].stats["lag_samples"] > 0 and runs["pilot"].stats["lagged"] == 0
    assert np.array_equal(runs["pilot"].centre, runs["none"].centre, equal_nan=True)
    assert np.array_equal(runs["pilot"].insertion_index, runs["none"].insertion_index)


def _by_hand(
    n: int, seed: int, lags: np.ndarray | None, closing: str, strip: float = 0.0
) -> tuple[SurfaceState, SurfaceSweep]:
    rng = np.random.default_rng(seed)
    radius = rng.uniform(0.5, 2.0, n)
    lo, hi = np.array([-6.0, -6.0, -20.0]), np.array([6.0, 6.0, 20.0])
    st = SurfaceState(SolidBatch.of_spheres(radius), radius, lo, hi)
    sw = SurfaceSweep(st, 0.999, 12.0, closing, strip)
    if lags is not None:
        sw.set_lags(lags)
    sw.run(rng)
    return st, sw


@pytest.mark.parametrize("closing", ["paced", "tail"])
def test_particles_waiting_until_the_stream_ends_are_offered_in_stream_order(
    closing: str,
) -> None:
    """Lags longer than the box: nothing is offered before the stream ends, then all in
    order, which is the run without lags."""
    n = 150  # about 70 % of what fills the box
    st0, _ = _by_hand(n, 5, None, closing)
    st1, sw1 = _by_hand(n, 5, np.full(n, 10**6, dtype=np.int64), closing)
    assert sw1.waiting == 0
    assert np.array_equal(st0.centre, st1.centre, equal_nan=True)
    assert np.array_equal(st0.order[: st0.count], st1.order[: st1.count])


def test_only_a_lagged_particle_is_overtaken_and_only_after_the_front_rose() -> None:
    n = 260
    rng = np.random.default_rng(6)
    small = rng.uniform(0.5, 2.0, n) < 0.9  # the same radii as _by_hand draws
    lags = np.where(small, 30, 0).astype(np.int64)
    st, sw = _by_hand(n, 6, lags, "paced")
    order = st.order[: st.count]
    overtaken = np.zeros(n, dtype=np.int64)
    latest = -1
    for i in order:
        overtaken[i] = max(0, latest - i)  # a lower bound: the latest drawn so far
        latest = max(latest, int(i))
    placed = sw.status[:n] == STATUS_PLACED
    assert (overtaken[placed & (lags == 0)] == 0).all()
    waited = placed & (lags > 0)
    assert waited.sum() > 20
    assert np.median(overtaken[waited]) > 5
    # each lagged particle is offered once the front top has risen by its lag
    z = st.centre[:, 2]
    pos = np.empty(n, dtype=np.int64)
    pos[order] = np.arange(st.count)
    top_before = np.maximum.accumulate(z[order])
    at_turn = placed & (lags == 0)
    j = np.flatnonzero(waited)
    j = j[(j > 0) & np.array([at_turn[:k].any() for k in j])]
    turn = np.array([pos[:k][at_turn[:k]].max() for k in j])
    rise = top_before[pos[j]] - top_before[turn]
    assert np.median(rise) > 0.5 * 30 * sw.delta


def test_the_pilot_measures_tops_only_with_the_zone_at_full_height() -> None:
    st, sw = _by_hand(400, 3, None, "tail")
    placed = sw.status[:400] == STATUS_PLACED
    top = sw.top_at[:400]
    assert (top[~placed] == -1).all()
    measured = top >= 0
    assert measured.any() and (top[measured] >= sw.nzone - 1).all()
    # a centre lies at most a zone (and two circumradii) below the top it was placed under
    z = st.centre[measured, 2] - st.lo[2]
    assert np.all(z <= (top[measured] + 1) * sw.delta + 4.0)
    assert np.all(z >= (top[measured] + 1 - sw.nzone) * sw.delta - 4.0)


@pytest.mark.parametrize("closing", ["tail", "prompt"])
def test_closings_that_leave_out_a_random_tail_still_do(closing: str) -> None:
    """Every particle drawn before the last one offered is offered: the rest is a suffix."""
    n = 700  # more than fill the box
    rng = np.random.default_rng(4)
    lags = np.where(rng.uniform(0.5, 2.0, n) < 1.0, 20, 0).astype(np.int64)
    _, sw = _by_hand(n, 4, lags, closing)
    status = sw.status[:n]
    offered = np.flatnonzero(status != STATUS_NOT_OFFERED)
    assert offered.max() < n - 1  # a tail is left out
    assert np.count_nonzero(status[: offered.max() + 1] == STATUS_NOT_OFFERED) == 0


def test_lags_with_columns_stay_overlap_free() -> None:
    data = scene(closing="paced", strip=16.0)
    data["domain"] = {"kind": "box", "width": 32.0, "height": 44.0, "depth": 16.0}
    packing = _pack(data)
    assert packing.stats["lagged"] > 0 and packing.stats["strips"] == 2
    report = regopack.verify(packing)
    assert report.ok, str(report)


def test_lagged_polyhedra_stay_overlap_free() -> None:
    shapes = {"kind": "polyhedron", "psi": 0.5}
    made = _pack(
        {
            **scene(),
            "count": 150,
            "domain": {"kind": "box", "width": 60.0, "height": 60.0, "depth": 60.0},
            "phases": [{"name": "a", "fraction": 1.0, "shape": shapes}],
            "insertion": {"kind": "available-surface", "order": "sweep", "lag": "none"},
        }
    )
    solids = made.solids
    radius = np.cbrt(3.0 * solids.volume / (4.0 * np.pi))
    lo, hi = np.array([-6.0, -6.0, -12.0]), np.array([6.0, 6.0, 12.0])
    st = SurfaceState(solids, radius, lo, hi)
    sw = SurfaceSweep(st, 0.999, 8.0, "paced", strip=6.0)
    lags = np.where(radius < np.median(radius), 25, 0).astype(np.int64)
    sw.set_lags(lags)
    sw.run(np.random.default_rng(3))
    placed = np.flatnonzero(sw.status[: len(solids)] == STATUS_PLACED)
    assert (lags[placed] > 0).sum() > 10
    world = [
        solids.vertices[solids.offsets[j] : solids.offsets[j + 1]] + st.centre[j] for j in placed
    ]
    report = verify_polyhedra(world, None, lo, hi)
    assert report.ok, str(report)


def _spheres_sweep(
    radius: np.ndarray, closing: str, strip: float = 0.0
) -> tuple[SurfaceState, SurfaceSweep]:
    lo, hi = np.array([-6.0, -6.0, -20.0]), np.array([6.0, 6.0, 20.0])
    st = SurfaceState(SolidBatch.of_spheres(radius), radius, lo, hi)
    return st, SurfaceSweep(st, 0.999, 12.0, closing, strip)


@pytest.mark.parametrize("closing", ["tail", "prompt"])
@pytest.mark.parametrize("queued", [True, False])
def test_only_a_refusal_at_its_turn_closes_a_column_or_retires_a_bin(
    closing: str, queued: bool
) -> None:
    radius = np.r_[np.full(40, 1.0), 50.0]  # the last one fits nowhere
    _, sw = _spheres_sweep(radius, closing)
    rng = np.random.default_rng(1)
    for i in range(40):
        sw.offer(i, rng)
    z = sw.zones[0]
    z.full = True  # as if its zone had reached the top
    lo = z.lo
    sw.offer(40, rng, queued=queued)
    assert sw.status[40] == STATUS_REFUSED
    if queued:
        assert not z.closed and z.lo == lo
    elif closing == "tail":
        assert z.closed
    else:
        assert z.lo == lo + 1


def test_a_waiting_particle_goes_to_its_home_column_first() -> None:
    radius = np.full(80, 1.0)
    _, sw = _spheres_sweep(radius, "paced", strip=6.0)
    rng = np.random.default_rng(2)
    for i in range(60):
        sw.offer(i, rng)
    tops = [z.hi if z.seeded else -1 for z in sw.zones]
    home = int(np.argmax(tops))  # the highest: the one a particle at its turn goes to last
    assert home != sw._choose(set())
    sw.offer(60, rng, queued=True, prefer=home)
    assert sw.status[60] == STATUS_PLACED and sw.cur == home


def test_waiting_particles_are_offered_once_the_top_reaches_their_bin_not_later(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """After each release, no particle still waits for a bin its column's top has reached
    (the top rising on as a full zone's bins retire), and none was offered before."""
    n = 420  # more than fill the box: the paced closing runs too
    rng = np.random.default_rng(8)
    radius = rng.uniform(0.5, 2.0, n)
    _, sw = _spheres_sweep(radius, "paced", strip=6.0)
    sw.set_lags(np.where(radius < 1.0, 30, 0).astype(np.int64))
    waited: dict[int, tuple[int, int]] = {}
    checks = {"released": 0, "offered": 0}

    def top(z: Any) -> int:
        return max(z.hi, z.lo + sw.nzone - 1) if z.full else z.hi

    wait, release, offer = SurfaceSweep._wait, SurfaceSweep._release, SurfaceSweep.offer

    def spy_wait(self: SurfaceSweep, i: int, home: int) -> bool:
        queued = wait(self, i, home)
        if queued:
            b = next(b for b, q in self.queues[home].items() if q and q[-1] == i)
            waited[i] = (home, b)
        return queued

    def spy_release(self: SurfaceSweep, rng: np.random.Generator, ended: bool) -> None:
        release(self, rng, ended)
        if self.flush or self.done:
            return
        for k, z in enumerate(self.zones):
            if z.seeded and not z.closed:
                assert all(b > top(z) for b in self.queues[k]), (k, top(z))
        checks["released"] += 1

    def spy_offer(self: SurfaceSweep, i: int, *args: Any, **kwargs: Any) -> None:
        if kwargs.get("queued") and self.flush != 1:
            home, b = waited[i]
            assert kwargs.get("prefer") == home
            assert top(self.zones[home]) >= b
            checks["offered"] += 1
        offer(self, i, *args, **kwargs)

    monkeypatch.setattr(SurfaceSweep, "_wait", spy_wait)
    monkeypatch.setattr(SurfaceSweep, "_release", spy_release)
    monkeypatch.setattr(SurfaceSweep, "offer", spy_offer)
    sw.run(rng)
    assert checks["offered"] > 30 and checks["released"] > 100
    assert any(z.full for z in sw.zones)


def test_the_even_closing_with_lags_leaves_no_particle_out() -> None:
    """Its waiting particles go at once when every zone is full: each left out is held."""
    data = scene(closing="even")
    data["seed"] = 4
    data["domain"] = {"kind": "box", "width": 16.0, "height": 64.0, "depth": 16.0}
    packing = _pack(data)
    s = packing.stats
    assert s["lagged"] > 0 and s["held"] > 0
    assert s["not_offered"] == 0
    assert packing.n_placed + s["refused"] + s["held"] == packing.n_particles


@pytest.mark.parametrize("closing", ["tail", "prompt", "even"])
def test_no_particle_waits_once_every_zone_is_at_the_top(closing: str) -> None:
    """These closings let every waiting particle go when the last zone reaches the top
    (the particles left out are then the stream's tail), and none waits after."""
    n = 700  # more than fill the box
    rng = np.random.default_rng(5)
    radius = rng.uniform(0.5, 2.0, n)
    _, sw = _spheres_sweep(radius, closing, strip=6.0)
    sw.set_lags(np.where(radius < 1.2, 30, 0).astype(np.int64))
    full_seen = waited = 0
    for i in range(n):  # the loop of SurfaceSweep.run
        if sw.done:
            break
        sw._release(rng, ended=False)
        if sw._all_full():
            full_seen += 1
            assert sw.waiting == 0 and sw.flush == 1
        if sw.done:
            break
        waits = sw.paced or not sw._all_full()
        if waits and sw._wait(i, sw._choose(set())):
            waited += 1
            continue
        sw.offer(i, rng)
    assert full_seen > 0 and waited > 20


def test_the_paced_closing_passes_over_only_particles_that_waited() -> None:
    """Particles still waiting when their column closes, or when the run ends, are left
    out; a particle without a lag never is (but for the stream's tail)."""
    n = 700  # more than fill the box
    rng = np.random.default_rng(5)
    radius = rng.uniform(0.5, 2.0, n)
    _, sw = _spheres_sweep(radius, "paced", strip=6.0)
    lags = np.where(radius < 1.2, 30, 0).astype(np.int64)
    sw.set_lags(lags)
    sw.run(rng)
    status = sw.status[:n]
    last = int(np.flatnonzero(status != STATUS_NOT_OFFERED).max())
    skipped = np.flatnonzero(status[:last] == STATUS_NOT_OFFERED)
    # only particles that waited are passed over, and some are
    assert skipped.shape[0] > 0 and (lags[skipped] > 0).all()

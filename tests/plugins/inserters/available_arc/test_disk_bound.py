"""Bounds on the disks a disk candidate can take: sound, used, and leaving packings unchanged."""

from __future__ import annotations

import math

import numpy as np
import pytest
from arc_helpers import octagon_population, pack
from hypothesis import given, settings
from hypothesis import strategies as st
from test_batches import _force_threads
from test_disk_path import _disks
from test_neighbours import HEXAGON, _rounded_population

from regopack.geometry.domain import Circle, ConvexPolygon, Domain, PeriodicRectangle, Rectangle
from regopack.plugins.common.walls import WALL_BOX
from regopack.plugins.inserters.available_arc import kernel
from regopack.plugins.inserters.available_arc.disk_bound import (
    SORT_IN_PLACE,
    covered,
    disk_bound,
    sort_covers,
)
from regopack.plugins.inserters.available_arc.rounded import disk_arcs
from regopack.plugins.inserters.available_arc.state import ArcState


def _free_angles(rk: float, r: float, c: np.ndarray, rad: np.ndarray, samples: int) -> int:
    """Oracle: how many of ``samples`` centres on the circle of radius ``rk + r`` lie outside
    every open disk ``(c[f], rad[f] + r)``."""
    theta = np.linspace(0.0, 2.0 * np.pi, samples, endpoint=False)
    p = (rk + r) * np.stack([np.cos(theta), np.sin(theta)], axis=1)
    d = np.linalg.norm(p[:, None, :] - c[None, :, :], axis=2)
    return int(np.count_nonzero((d >= rad[None, :] + r).all(axis=1)))


def _ring(rng: np.random.Generator, rk: float, m: int, spread: float) -> tuple[np.ndarray, ...]:
    """``m`` disks around a candidate of radius ``rk`` at the origin, none overlapping it."""
    rad = rk * np.exp(rng.uniform(-spread, spread, m))
    ang = np.sort(rng.uniform(0.0, 2.0 * np.pi, m))
    dist = rk + rad + rk * rng.uniform(0.0, 0.3, m)
    c = np.stack([dist * np.cos(ang), dist * np.sin(ang)], axis=1)
    return c, rad


def test_three_touching_equal_disks_shut_a_fourth_at_their_own_size() -> None:
    """Hexagonal packing: the pores around a disk of radius 1 take disks below radius 1."""
    ang = np.array([0.0, 2.0, 4.0]) * np.pi / 3.0
    c = 2.0 * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    rad = np.ones(3)
    bound = disk_bound(1.0, 2.0, 0.1, 3, c[:, 0].copy(), c[:, 1].copy(), rad)
    # six halvings of log(20): the bound lies within 20 ** (1 / 64) of the true 1.0
    assert 1.0 <= bound <= 1.05
    assert _free_angles(1.0, 0.99, c, rad, 100_000) > 0


def test_a_gap_no_interferer_closes_gives_no_bound() -> None:
    c = np.array([[2.0, 0.0], [0.0, 2.0]])
    rad = np.ones(2)
    assert disk_bound(1.0, 3.0, 0.1, 2, c[:, 0].copy(), c[:, 1].copy(), rad) == math.inf


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    m=st.integers(2, 24),
    spread=st.sampled_from([0.0, 0.7, 2.3, 4.6]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
)
def test_no_disk_at_or_above_the_bound_fits_anywhere(
    seed: int, m: int, spread: float, scale: float
) -> None:
    """Soundness against a dense sampling of the circle of centres (size ratios up to 10^4)."""
    rng = np.random.default_rng(seed)
    rk = scale
    c, rad = _ring(rng, rk, m, spread)
    r_floor = 1e-2 * rk
    r_fail = rk * float(np.exp(rng.uniform(-2.0, 2.0)))
    bound = disk_bound(rk, r_fail, r_floor, m, c[:, 0].copy(), c[:, 1].copy(), rad)
    if bound == math.inf:
        # no bound means the failed disk itself was not shown shut with margin
        return
    assert r_floor <= bound <= r_fail
    for r in (bound, bound * (1.0 + 1e-9), 1.5 * bound, r_fail, 10.0 * r_fail):
        assert _free_angles(rk, r, c, rad, 20_000) == 0, r


def _arcs(rk: float, r: float, c: np.ndarray, rad: np.ndarray) -> int:
    """The kernel's own analysis of a disk of radius ``r`` against ``rk`` (no walls in reach)."""
    far = 1e6 * (rk + r + float(np.abs(c).max()))
    box = np.array([-far, far, -far, far])
    arcs = disk_arcs(
        rk + r, 0.0, 0.0, len(rad), c[:, 0].copy(), c[:, 1].copy(), rad + r,
        WALL_BOX, np.zeros((1, 3)), box, np.zeros(1), np.zeros(1), np.zeros(1), 0.0,
    )  # fmt: skip
    return int(arcs.shape[0])


@settings(max_examples=80, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    m=st.integers(2, 40),
    spread=st.sampled_from([0.0, 0.7, 2.3, 4.6]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
    gap=st.sampled_from([0.0, 1e-9, 1e-6, 1e-3]),
)
def test_the_analysis_finds_no_arc_at_or_above_the_bound(
    seed: int, m: int, spread: float, scale: float, gap: float
) -> None:
    """Soundness against the analysis itself, which sees gaps of any width: interferers
    that touch the candidate (``gap`` 0) or nearly, at every scale and size ratio."""
    rng = np.random.default_rng(seed)
    rk = scale
    rad = rk * np.exp(rng.uniform(-spread, spread, m))
    ang = np.sort(rng.uniform(0.0, 2.0 * np.pi, m))
    dist = (rk + rad) * (1.0 + gap)
    c = np.stack([dist * np.cos(ang), dist * np.sin(ang)], axis=1)
    r_fail = rk * float(np.exp(rng.uniform(-3.0, 2.0)))
    bound = disk_bound(rk, r_fail, 1e-3 * rk, m, c[:, 0].copy(), c[:, 1].copy(), rad)
    if bound == math.inf:
        return
    for r in (bound, bound * (1.0 + 1e-12), 1.1 * bound, r_fail, 100.0 * r_fail):
        assert _arcs(rk, r, c, rad) == 0, r


@pytest.mark.parametrize("eps", [1e-6, 3e-7, 1e-7, 1e-8])
def test_a_disk_just_small_enough_for_a_closing_pore_still_finds_it(eps: float) -> None:
    """Three unit disks touch a unit candidate 120 degrees apart: its pores close at radius 1.
    A disk of radius 1 - eps fits in arcs about eps wide, after a larger one proved a bound."""
    ang = np.array([0.0, 2.0, 4.0]) * np.pi / 3.0
    c = 2.0 * np.stack([np.cos(ang), np.sin(ang)], axis=1)
    rad = np.ones(3)
    assert _arcs(1.0, 1.0 - eps, c, rad) > 0
    bound = disk_bound(1.0, 1.5, 1.0 - eps, 3, c[:, 0].copy(), c[:, 1].copy(), rad)
    assert bound > 1.0 - eps
    # and through the kernel: the small disk goes where it goes without the bounds
    found = []
    for bounds in (True, False):
        r = np.array([1.0, 1.0, 1.0, 1.0, 1.5, 1.0 - eps])
        st_ = ArcState(
            _disks(r, np.random.default_rng(0)), Rectangle.centred(40.0, 40.0),
            t=0.999, tau=None, linear=False,
        )  # fmt: skip
        st_.packed.ipar[kernel.I_BOUND] = 1 if bounds else 0
        st_.insert(0, 0.0, 0.0)
        for j in range(3):
            st_.insert(j + 1, float(c[j, 0]), float(c[j, 1]))
        kernel.analyze_candidate(0, 4, st_.begin_particle(4), *_state(st_))
        k, arcs = st_.find_site(5, 0, st_.begin_particle(5))
        found.append((k, arcs.tobytes()))
    assert found[0] == found[1]


def _state(st_: ArcState) -> tuple[object, ...]:
    return st_.outlines, st_.packed, st_.work, st_.rounded


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), m=st.integers(2, 24), spread=st.sampled_from([0.0, 2.3]))
def test_a_covered_circle_stays_covered_for_larger_disks(seed: int, m: int, spread: float) -> None:
    rng = np.random.default_rng(seed)
    c, rad = _ring(rng, 1.0, m, spread)
    dist = np.hypot(c[:, 0], c[:, 1])
    angle = np.arctan2(c[:, 1], c[:, 0])
    lo = np.empty(2 * m)
    hi = np.empty(2 * m)
    radii = np.exp(np.linspace(-5.0, 3.0, 60))
    shut = [covered(1.0, float(r), m, dist, angle, rad, lo, hi) for r in radii]
    first = shut.index(True) if True in shut else len(shut)
    assert all(shut[first:])


def _bounds_off(monkeypatch: pytest.MonkeyPatch) -> None:
    original = ArcState.__init__

    def init(self: ArcState, *args: object, **kwargs: object) -> None:
        original(self, *args, **kwargs)  # type: ignore[arg-type]
        self.packed.ipar[kernel.I_BOUND] = 0

    monkeypatch.setattr(ArcState, "__init__", init)


def _counts(stats: dict[str, object]) -> dict[str, object]:
    """A run's statistics other than its times and whether a partner proved bounds (the
    analyses counted include skipped ones)."""
    return {k: v for k, v in stats.items() if "time" not in k and k != "partner"}


DOMAINS: dict[str, Domain] = {
    "rectangle": Rectangle.centred(90.0, 80.0, (2.0, -1.0)),
    "circle": Circle(1.0, 2.0, 48.0),
    "polygon": ConvexPolygon(HEXAGON),
    "periodic": PeriodicRectangle(-40.0, 45.0, -35.0, 40.0),
}


@pytest.mark.parametrize("order", ["paper", "sweep"])
@pytest.mark.parametrize("kind", list(DOMAINS))
def test_disks_pack_the_same_with_and_without_the_bounds(
    kind: str, order: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The bounds skip only analyses that find nothing, in every domain kind and order."""
    out = []
    for bounds in (True, False):
        if not bounds:
            _bounds_off(monkeypatch)
        pop = _rounded_population(400, 7, "disks")
        rng = np.random.default_rng(7)
        res = pack(pop, DOMAINS[kind], rng, order=order)
        out.append((res.centre.tobytes(), res.insertion_index.tobytes(), _counts(res.stats)))
    assert out[0] == out[1]


def test_disks_pack_the_same_on_two_threads_with_the_bounds(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The exact scans of the paced closing, spread over threads, read the bounds and
    prove new ones on each thread; the calling thread merges them after each batch."""
    from regopack.api.functions import pack_and_summarise

    _force_threads(monkeypatch, 2)
    overrides = {f"phases.{k}.shape": {"kind": "disk"} for k in range(6)}
    out = []
    for bounds in (True, False):
        if not bounds:
            _bounds_off(monkeypatch)
        run = pack_and_summarise(
            "dem", seed=2, **{"domain.width": 150.0, "domain.height": 300.0, **overrides}
        )
        assert run.summary["threads"] == 2
        out.append((run.packing.centre.tobytes(), _counts(run.packing.stats)))
    assert out[0] == out[1]


def _shut(pop: object, tau: float | None = None) -> int:
    st_ = ArcState(pop, Rectangle.centred(60.0, 60.0), t=0.999, tau=tau, linear=False)  # type: ignore[arg-type]
    st_.pack_range(0, len(pop), np.random.default_rng(2))  # type: ignore[arg-type]
    return int(np.isfinite(st_.packed.shut).sum())


def test_the_bounds_are_found_for_disks_only_and_not_under_the_tau_screening() -> None:
    rng = np.random.default_rng(2)
    radius = rng.uniform(0.5, 3.0, 500)
    assert _shut(_disks(radius, rng)) > 20
    assert _shut(_disks(radius, rng), tau=0.9) == 0
    assert _shut(_rounded_population(500, 2, "mixed")) == 0
    assert _shut(octagon_population(radius, rng)) == 0


@pytest.mark.parametrize("shut_from", [0, 40])
def test_an_exact_scan_counts_the_candidates_it_passes_over_as_the_sequential_one(
    shut_from: int,
) -> None:
    """Batched or not, a scan counts one empty analysis per shut candidate it passes, also
    after its last batch slot (every candidate, or all but the first 40, marked shut)."""
    from regopack.plugins.inserters.available_arc import batches, sweep

    rng = np.random.default_rng(8)
    radius = rng.uniform(0.5, 2.0, 400)
    counts = []
    for threads in (0, 2):
        pop = _disks(radius, np.random.default_rng(8))
        st_ = ArcState(pop, Rectangle.centred(60.0, 90.0), t=0.999, tau=None, linear=False)
        sw = sweep.Sweep(len(pop), 90.0, 12.0, width=60.0)
        sw.run(0, 300, st_.outlines, st_.packed, st_.work, np.random.default_rng(8), st_.rounded)
        placed = st_.packed.order[: st_.counter(kernel.I_COUNT)]
        st_.packed.shut[placed[shut_from:]] = 0.0  # shut for every disk
        helpers = batches.new_helpers(st_.work, st_.packed, threads)
        before = st_.counter(kernel.I_ANALYSES)
        mq = st_.begin_particle(350)
        k = sweep._exhaustive(
            350, mq, st_.outlines, st_.packed, st_.work, np.random.default_rng(1),
            st_.rounded, 0, 0, sw.bins, helpers,
        )  # fmt: skip
        counts.append((k, st_.counter(kernel.I_ANALYSES) - before))
    assert counts[0] == counts[1]
    assert counts[0][1] > 0


@pytest.mark.parametrize("k", [0, 1, 2, 7, SORT_IN_PLACE, SORT_IN_PLACE + 1, 200, 5000])
def test_sort_covers_orders_pairs_by_lower_end(k: int) -> None:
    rng = np.random.default_rng(k)
    lo = np.round(rng.uniform(-1.0, 7.0, k + 3), 1)  # ties among the lower ends
    hi = lo + rng.uniform(0.0, 2.0, k + 3)
    pairs = sorted(zip(lo[:k].tolist(), hi[:k].tolist(), strict=True))
    tail = (lo[k:].copy(), hi[k:].copy())
    sort_covers(lo, hi, k)
    assert np.all(np.diff(lo[:k]) >= 0.0)
    assert sorted(zip(lo[:k].tolist(), hi[:k].tolist(), strict=True)) == pairs  # pairs kept
    assert np.array_equal(lo[k:], tail[0]) and np.array_equal(hi[k:], tail[1])

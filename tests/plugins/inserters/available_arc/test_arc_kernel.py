"""Available arcs against an independent dense-sampling oracle (shapely)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from arc_helpers import mixed_population
from hypothesis import given, settings
from hypothesis import strategies as st

from regopack.geometry.domain import PeriodicRectangle, Rectangle
from regopack.plugins.inserters.available_arc import kernel
from regopack.plugins.inserters.available_arc.state import ArcState, envelope_cache

# analyze_candidate is called with ``rounded=None`` spelt out, as the packing loops call it:
# leaving it to its default would compile a specialization of the kernel for these tests alone
MARGIN = 1e-3  # radians kept away from arc ends, where the oracle is ambiguous
OVERLAP = 1e-12  # relative overlap area the oracle counts as interference


def _setup(seed: int, n_neighbours: int, domain: Rectangle, ratio: float = 1.0, scale: float = 1.0):
    """Candidate 0 at the domain centre, neighbours around it, new particle last."""
    rng = np.random.default_rng(seed)
    radius = scale * rng.uniform(1.0, 3.0, size=n_neighbours + 2)
    radius[-1] *= ratio
    pop = mixed_population(radius, rng)
    st_ = ArcState(pop, domain, t=1.0, tau=None, linear=False)
    cx, cy = domain.center
    st_.insert(0, cx, cy)
    reach = 3.0 * scale * (2.0 + 2.0 * ratio)
    for j in range(1, n_neighbours + 1):
        ang = rng.uniform(0, 2 * np.pi)
        d = rng.uniform(0.5, 1.0) * reach
        st_.insert(j, cx + d * math.cos(ang), cy + d * math.sin(ang))
    i = n_neighbours + 1
    mq = st_.begin_particle(i)
    arcs = kernel.analyze_candidate(0, i, mq, st_.outlines, st_.packed, st_.work, None)
    return pop, st_, i, arcs


def _oracle(pop, st_, i: int, domain: Rectangle, angles: np.ndarray) -> np.ndarray:
    """True where particle i, on candidate 0's envelope at each polar angle, is free."""
    P = pop.shapes.outline(0)
    Q = pop.shapes.outline(i)
    hull = shapely.MultiPoint((P[:, None, :] - Q[None, :, :]).reshape(-1, 2)).convex_hull
    far = 10.0 * math.sqrt(hull.area) + 10.0 * np.abs(np.asarray(hull.bounds)).max()
    others = [
        shapely.Polygon(pop.shapes.outline(j) + (st_.packed.cx[j], st_.packed.cy[j]))
        for j in range(1, i)
    ]
    box = shapely.box(domain.xmin, domain.ymin, domain.xmax, domain.ymax)
    q_area = math.pi * pop.radius[i] ** 2
    free = np.empty(len(angles), dtype=bool)
    for a, ang in enumerate(angles):
        ray = shapely.LineString([(0, 0), (far * math.cos(ang), far * math.sin(ang))])
        hit = ray.intersection(hull.exterior)
        pt = (
            np.asarray(hit.coords[0])
            if hit.geom_type == "Point"
            else np.asarray(hit.geoms[0].coords[0])
        )
        qpoly = shapely.Polygon(Q + pt + (st_.packed.cx[0], st_.packed.cy[0]))
        ok = qpoly.area - qpoly.intersection(box).area <= OVERLAP * q_area
        if ok:
            for o in others:
                if qpoly.intersects(o) and qpoly.intersection(o).area > OVERLAP * min(
                    q_area, o.area
                ):
                    ok = False
                    break
        free[a] = ok
    return free


def _classify(arcs: np.ndarray, angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Predicted freedom of each angle and whether it is clear of every arc end."""
    inside = np.zeros(len(angles), dtype=bool)
    clear = np.ones(len(angles), dtype=bool)
    for lo, hi in arcs:
        rel = np.mod(angles - lo, 2 * np.pi)
        inside |= rel <= hi - lo
        for end in (lo, hi):
            d = np.abs(np.mod(angles - end + np.pi, 2 * np.pi) - np.pi)
            clear &= d > MARGIN
    return inside, clear


@given(seed=st.integers(0, 2**32 - 1), n=st.integers(0, 9), walls=st.booleans())
@settings(max_examples=60, deadline=None)
def test_arcs_match_dense_sampling(seed: int, n: int, walls: bool) -> None:
    half = 6.0 if walls else 1e3
    domain = Rectangle(-half, half, -half, half)
    pop, st_, i, arcs = _setup(seed, n, domain)
    assert np.all(arcs[:, 1] > arcs[:, 0])
    assert np.sum(arcs[:, 1] - arcs[:, 0]) <= 2 * np.pi + 1e-12
    angles = np.linspace(0, 2 * np.pi, 721)[:-1] + 1e-4
    predicted, clear = _classify(arcs, angles)
    truth = _oracle(pop, st_, i, domain, angles)
    mismatch = (predicted != truth) & clear
    assert not mismatch.any(), f"angles {angles[mismatch][:5]} predicted {predicted[mismatch][:5]}"


@pytest.mark.parametrize("ratio", [1e-4, 1e-2, 1e2, 1e4])
def test_arcs_match_at_extreme_size_ratios(ratio: float) -> None:
    domain = Rectangle(-1e7, 1e7, -1e7, 1e7)
    pop, st_, i, arcs = _setup(11, 4, domain, ratio=ratio)
    angles = np.linspace(0, 2 * np.pi, 361)[:-1] + 1e-4
    predicted, clear = _classify(arcs, angles)
    truth = _oracle(pop, st_, i, domain, angles)
    assert not ((predicted != truth) & clear).any()


@pytest.mark.parametrize("scale", [1e-6, 1e6])
def test_arcs_scale_with_lengths(scale: float) -> None:
    base = Rectangle(-1e3, 1e3, -1e3, 1e3)
    scaled = Rectangle(-1e3 * scale, 1e3 * scale, -1e3 * scale, 1e3 * scale)
    _, _, _, arcs = _setup(5, 6, base)
    _, _, _, arcs_scaled = _setup(5, 6, scaled, scale=scale)
    assert arcs.shape == arcs_scaled.shape
    assert np.allclose(arcs, arcs_scaled, atol=1e-9)


def test_free_envelope_is_one_full_turn() -> None:
    domain = Rectangle(-1e3, 1e3, -1e3, 1e3)
    _, _, _, arcs = _setup(3, 0, domain)
    assert arcs.shape == (1, 2)
    assert arcs[0, 1] - arcs[0, 0] == pytest.approx(2 * np.pi, abs=1e-12)


def test_arc_through_the_first_vertex_is_one_interval() -> None:
    """An interferer opposite the envelope's first vertex leaves one arc that wraps through it."""
    rng = np.random.default_rng(0)
    radius = np.array([2.0, 2.0, 1.0])
    pop = mixed_population(radius, rng)
    domain = Rectangle(-1e3, 1e3, -1e3, 1e3)
    st_ = ArcState(pop, domain, t=1.0, tau=None, linear=False)
    st_.insert(0, 0.0, 0.0)
    i = 2
    mq = st_.begin_particle(i)
    # the envelope's first vertex
    kernel.minkowski_envelope(
        0,
        *st_.outlines[:6],
        *st_.work[:5],
        mq,
        st_.work.wx,
        st_.work.wy,
        st_.work.wex,
        st_.work.wey,
    )
    first = math.atan2(st_.work.wy[0], st_.work.wx[0])
    st_.insert(1, 5.0 * math.cos(first + np.pi), 5.0 * math.sin(first + np.pi))
    arcs = kernel.analyze_candidate(0, i, mq, st_.outlines, st_.packed, st_.work, None)
    assert arcs.shape == (1, 2)
    assert arcs[0, 0] < first < arcs[0, 1]
    assert arcs[0, 1] - arcs[0, 0] < 2 * np.pi


def test_fully_covered_candidate_has_no_arcs() -> None:
    rng = np.random.default_rng(2)
    pop = mixed_population(np.array([1.0] + [1.5] * 12 + [1.0]), rng)
    domain = Rectangle(-1e3, 1e3, -1e3, 1e3)
    st_ = ArcState(pop, domain, t=1.0, tau=None, linear=False)
    st_.insert(0, 0.0, 0.0)
    for j in range(1, 13):
        a = 2 * np.pi * j / 12
        st_.insert(
            j, 2.2 * math.cos(a), 2.2 * math.sin(a)
        )  # a ring overlapping the candidate's surroundings
    mq = st_.begin_particle(13)
    arcs = kernel.analyze_candidate(0, 13, mq, st_.outlines, st_.packed, st_.work, None)
    assert arcs.shape == (0, 2)


def _cluster() -> tuple[ArcState, int]:
    """A 5 x 5 block of touching-distance particles, every one a candidate; new particle last."""
    rng = np.random.default_rng(8)
    n = 25
    pop = mixed_population(np.append(rng.uniform(1.2, 1.8, n), 1.0), rng)
    st_ = ArcState(pop, Rectangle(-20.0, 20.0, -20.0, 20.0), t=1.0, tau=None, linear=False)
    for j in range(n):
        st_.insert(j, 3.1 * (j % 5) - 6.2, 3.1 * (j // 5) - 6.2)
    return st_, n


@pytest.mark.parametrize("slots", [*range(1, 13), 512])
def test_cached_envelopes_give_the_arcs_of_fresh_ones(slots: int) -> None:
    """Candidates analysed in a row share the envelope cache (interferers met again reuse
    their envelopes, the cache refills when full, and fewer slots than interferers bypass
    it): the arcs are those of a fresh cache, bit for bit, and every envelope the cache
    holds is its particle's."""
    st_, i = _cluster()
    g, s = st_.outlines, st_.packed
    fresh = []
    for k in range(i):
        mq = st_.begin_particle(i)  # a new generation: nothing cached
        fresh.append(kernel.analyze_candidate(k, i, mq, g, s, st_.work, None))
    w0 = st_.work
    width = w0.cache_x.shape[1]
    w = w0._replace(ckey=np.full_like(w0.ckey, -1), **envelope_cache(slots, width))
    mq = kernel.begin_particle(i, g, s, w)
    order = np.random.default_rng(slots).permutation(np.tile(np.arange(i), 3))
    for k in order:
        arcs = kernel.analyze_candidate(k, i, mq, g, s, w, None)
        assert arcs.tobytes() == fresh[k].tobytes(), k
        assert s.ipar[kernel.I_CUSED] <= slots  # no slot beyond the cache
    gen = s.ipar[kernel.I_GEN]
    held = np.flatnonzero(w.ckey == gen)
    if slots == 512:  # room for all: every particle's envelope made once, and kept
        assert held.size == i
    for o in held:
        sl = w.cslot[o]
        m = kernel.minkowski_envelope(o, *g[:6], *w[:5], mq, w0.wx, w0.wy, w0.wex, w0.wey)
        assert w.cache_n[sl] == m
        for got, want in zip(
            (w.cache_x, w.cache_y, w.cache_ex, w.cache_ey),
            (w0.wx, w0.wy, w0.wex, w0.wey),
            strict=True,
        ):
            assert got[sl, :m].tobytes() == want[:m].tobytes()
        assert w.cache_rad[sl] == math.sqrt(np.max(w0.wx[:m] ** 2 + w0.wy[:m] ** 2))


def _ringed(m: int = 80, periodic: bool = False) -> tuple[ArcState, int]:
    """A large candidate ringed by ``m`` small particles, all interferers of a new one;
    in a periodic domain the ring crosses the sides."""
    rng = np.random.default_rng(5)
    pop = mixed_population(np.array([12.0] + [0.9] * m + [0.8]), rng)
    domain = PeriodicRectangle(0.0, 100.0, 0.0, 100.0) if periodic else Rectangle(-50, 50, -50, 50)
    st_ = ArcState(pop, domain, t=1.0, tau=None, linear=False)
    st_.insert(0, 0.0, 0.0)
    for j in range(1, m + 1):
        a = 2 * np.pi * j / m + 0.3 * rng.random()
        x, y = 13.5 * math.cos(a), 13.5 * math.sin(a)
        st_.insert(j, x % 100.0 if periodic else x, y % 100.0 if periodic else y)
    return st_, m + 1


def _block(domain: Rectangle) -> tuple[ArcState, int]:
    """The 5 x 5 block of ``_cluster`` at the lower left corner of ``domain``."""
    rng = np.random.default_rng(8)
    n = 25
    pop = mixed_population(np.append(rng.uniform(1.2, 1.8, n), 1.0), rng)
    st_ = ArcState(pop, domain, t=1.0, tau=None, linear=False)
    for j in range(n):
        st_.insert(j, 3.1 * (j % 5) + 0.4, 3.1 * (j // 5) + 0.4)
    return st_, n


def _wrapped() -> tuple[ArcState, int]:
    """The block in a periodic domain 4.1 wider: its particles meet images across the sides."""
    return _block(PeriodicRectangle(0.0, 16.5, 0.0, 16.5))


SCENES = {
    "cluster": _cluster,
    "ring of 62": lambda: _ringed(62),  # up to FOUND_SLOTS interferers: the scratch
    "ring of 80": _ringed,  # more: arrays of its own
    "wrapped": _wrapped,
    "wrapped ring of 100": lambda: _ringed(100, periodic=True),  # image slots past 64
}


@pytest.mark.parametrize("name", SCENES)
def test_scratch_and_allocated_arrays_give_the_same_arcs(name: str) -> None:
    """An analysis of sharp polygons works in its thread's scratch (``fs`` rows, and
    ``found_q`` for the slots, up to FOUND_SLOTS interferers) or in arrays of its own:
    the arcs are the same bit for bit, with and without periodic images."""
    st_, i = SCENES[name]()
    g, s, w = st_.outlines, st_.packed, st_.work
    own = w._replace(fs=np.empty((kernel.SCRATCH_ROWS, 0)))  # too narrow: it allocates
    seen_arcs = seen_empty = 0
    for k in range(i):
        mq = st_.begin_particle(i)
        w.fs[:4] = np.nan  # rows the scratch analysis must write before it reads them
        scratch = kernel.analyze_candidate(k, i, mq, g, s, w, None).copy()
        mq = kernel.begin_particle(i, g, s, own)
        allocated = kernel.analyze_candidate(k, i, mq, g, s, own, None)
        assert scratch.shape[1:] == allocated.shape[1:] == (2,)
        assert scratch.tobytes() == allocated.tobytes(), k
        seen_arcs += scratch.shape[0] > 0
        seen_empty += scratch.shape[0] == 0
    assert seen_arcs > 0 and seen_empty > 0


def test_the_scratch_holds_the_offsets_and_slots() -> None:
    """The scratch path runs: after an analysis with nf interferers, row 0 of ``fs`` holds
    their x offsets and ``found_q`` their envelope-cache slots."""
    st_, i = _ringed(62)
    g, s, w = st_.outlines, st_.packed, st_.work
    mq = st_.begin_particle(i)
    w.found_q[:] = -7
    kernel.analyze_candidate(0, i, mq, g, s, w, None)
    nf = 62
    assert sorted(w.found_q[:nf]) == list(range(nf))  # a fresh cache: slots 0 .. nf - 1
    assert np.all(w.found_q[nf:] == -7)
    found = np.flatnonzero(w.ckey == s.ipar[kernel.I_GEN])
    np.testing.assert_array_equal(np.sort(w.fs[0, :nf]), np.sort(s.cx[found] - s.cx[0]))


def test_the_periodic_block_meets_its_images() -> None:
    """The wrapped block's arcs differ from those of the same block in open space, so an
    image's offset read wrong (a slot written before its image query is read) shows."""
    wrapped, i = _wrapped()
    walled, _ = _block(Rectangle(-100.0, 100.0, -100.0, 100.0))
    differ = 0
    for k in range(i):
        arcs = []
        for st_ in (wrapped, walled):
            mq = st_.begin_particle(i)
            arcs.append(
                kernel.analyze_candidate(k, i, mq, st_.outlines, st_.packed, st_.work, None)
            )
        differ += arcs[0].tobytes() != arcs[1].tobytes()
    assert differ > 0


def test_a_cut_analysis_stops_with_no_arcs() -> None:
    """A partner's analysis ends with no arcs once its cut word reaches its id, else runs."""
    domain = Rectangle(-1e3, 1e3, -1e3, 1e3)
    _, st_, i, arcs = _setup(3, 4, domain)
    assert arcs.shape[0] > 0
    mq = st_.begin_particle(i)
    g, s, w = st_.outlines, st_.packed, st_.work
    words = np.array([0, 7], dtype=np.int64)
    run = kernel.analyze_candidate(0, i, mq, g, s, w, None, (words, 1, 8))
    assert run.tobytes() == arcs.tobytes()
    for cut_id in (7, 6):
        assert kernel.analyze_candidate(0, i, mq, g, s, w, None, (words, 1, cut_id)).shape == (0, 2)


def test_sample_angle_is_uniform_over_union() -> None:
    arcs = np.array([[0.0, 1.0], [2.0, 4.0]])
    assert kernel.sample_angle(arcs, 0.0) == 0.0
    assert kernel.sample_angle(arcs, 0.5) == pytest.approx(2.5)
    assert kernel.sample_angle(arcs, 1 / 3 - 1e-12) == pytest.approx(1.0)
    assert kernel.sample_angle(arcs, 1.0) == pytest.approx(4.0)

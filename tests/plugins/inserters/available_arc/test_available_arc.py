"""The available-arc inserter end to end, checked by the shapely oracle."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from arc_helpers import as_packing, change5_population, octagon_population, pack
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from regopack.geometry.domain import Rectangle
from regopack.geometry.population import Population
from regopack.plugins.density.eta import EtaConfig, EtaController
from regopack.plugins.inserters.available_arc import AvailableArc, AvailableArcConfig
from regopack.registry.interfaces import DensityController, InsertionResult
from regopack.testing import extreme_radii
from regopack.verification.polygons import verify

_change5_population = change5_population
_pack = pack
_packing = as_packing


def _check(pop: Population, res: InsertionResult, domain: Rectangle) -> None:
    report = verify(_packing(pop, res, domain))
    assert report.ok, str(report)


def test_small_scene_has_no_overlaps_and_is_dense() -> None:
    pop, rng = _change5_population(700, 1)
    domain = Rectangle.centred(150.0, 150.0)
    res = _pack(pop, domain, rng)
    _check(pop, res, domain)
    packing = _packing(pop, res, domain)
    phi = packing.area()[packing.placed].sum() / domain.area
    assert phi > 0.75
    assert res.stats["candidate_analyses"] >= res.stats["empty_analyses"]


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_linear_scan_and_indexed_search_give_identical_packings(seed: int) -> None:
    domain = Rectangle.centred(120.0, 90.0, (3.0, -7.0))
    results = []
    for search in ("linear", "indexed"):
        pop, rng = _change5_population(450, seed)
        results.append(_pack(pop, domain, rng, search=search, eta=5.0 * (seed - 1)))
    assert np.array_equal(results[0].centre, results[1].centre, equal_nan=True)
    assert np.array_equal(results[0].insertion_index, results[1].insertion_index)
    assert results[0].stats["candidate_analyses"] == results[1].stats["candidate_analyses"]


def test_same_seed_same_packing_bit_for_bit() -> None:
    domain = Rectangle.centred(100.0, 100.0)
    pop, rng = _change5_population(300, 7)
    a = _pack(pop, domain, rng, eta=10.0)
    pop, rng = _change5_population(300, 7)
    b = _pack(pop, domain, rng, eta=10.0)
    assert a.centre.tobytes() == b.centre.tobytes()
    pop, rng = _change5_population(300, 8)
    c = _pack(pop, domain, rng, eta=10.0)
    assert a.centre.tobytes() != c.centre.tobytes()


class PythonEta(DensityController):
    """The eta rule written in plain Python, as a third-party controller would be."""

    def __init__(self, eta: float) -> None:
        self.eta = eta

    def shrink(self, arcs, r_new, r_candidate, rng):
        out = []
        for lo, hi in arcs:
            xi = rng.random()
            delta = max(0.0, self.eta + xi - 1.0) / 100.0 * (2.0 * r_new / (r_candidate + r_new))
            if hi - delta > lo + delta:
                out.append((lo + delta, hi - delta))
        return np.array(out, dtype=np.float64).reshape(-1, 2)


@pytest.mark.parametrize("eta", [5.0, 15.0])
def test_python_controller_matches_compiled_path(eta: float) -> None:
    domain = Rectangle.centred(90.0, 90.0)
    pop, rng = _change5_population(300, 4)
    compiled = AvailableArc(AvailableArcConfig()).pack(
        pop, domain, EtaController(EtaConfig(eta=eta)), rng
    )
    pop, rng = _change5_population(300, 4)
    python = AvailableArc(AvailableArcConfig()).pack(pop, domain, PythonEta(eta), rng)
    assert np.array_equal(compiled.centre, python.centre, equal_nan=True)


def test_phi_decreases_with_eta() -> None:
    domain = Rectangle.centred(120.0, 120.0)
    phis = []
    for eta in (0.0, 20.0, 40.0):
        pop, rng = _change5_population(900, 11)
        res = _pack(pop, domain, rng, eta=eta)
        _check(pop, res, domain)
        p = _packing(pop, res, domain)
        phis.append(p.area()[p.placed].sum() / domain.area)
    assert phis[0] > phis[1] > phis[2]


def test_every_particle_after_the_first_touches_a_neighbour_or_wall() -> None:
    domain = Rectangle.centred(80.0, 80.0)
    pop, rng = _change5_population(250, 5)
    res = _pack(pop, domain, rng)
    p = _packing(pop, res, domain)
    order = p.placed_in_order()
    geoms = p.to_shapely(order)
    box = shapely.box(domain.xmin, domain.ymin, domain.xmax, domain.ymax).exterior
    tree = shapely.STRtree(geoms)
    for j in range(1, len(order)):
        r = p.radius[order[j]]
        near = tree.query(geoms[j], predicate="dwithin", distance=1e-6 * r)
        near = near[near != j]
        touching = len(near) > 0 or shapely.distance(geoms[j], box) <= 1e-9 * r
        assert touching, f"particle {order[j]} floats"
    # the particle it was placed against is among the first j placed ones
    assert res.placed.sum() == len(order)


def test_tau_rule_and_random_first_particle_run() -> None:
    domain = Rectangle.centred(100.0, 100.0)
    pop, rng = _change5_population(400, 6)
    res = _pack(pop, domain, rng, interference="tau", tau=0.65, first="random")
    assert res.placed.sum() > 250
    first = int(np.flatnonzero(res.insertion_index == 0)[0])
    assert not np.allclose(res.centre[first], domain.center)


def test_particle_larger_than_domain_is_not_placed() -> None:
    domain = Rectangle.centred(10.0, 10.0)
    rng = np.random.default_rng(0)
    pop = octagon_population(np.array([20.0, 1.0, 1.0]), rng)
    res = _pack(pop, domain, rng)
    assert list(res.insertion_index) == [-1, 0, 1]
    _check(pop, res, domain)


@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(2, 60),
    ratio=st.sampled_from([1.0, 10.0, 1e2, 1e4]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
    psi=st.sampled_from([0.01, 0.25, 1.0, 1000.0]),
    a=st.sampled_from([0.05, 1 / 3, 1.0]),
    eta=st.sampled_from([0.0, 30.0]),
    interference=st.sampled_from(["exact", "exact", "tau"]),
)
@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_no_overlap_in_random_small_scenes(
    seed, n, ratio, scale, psi, a, eta, interference
) -> None:
    rng = np.random.default_rng(seed)
    radius = extreme_radii(n, ratio, scale, rng)  # the extremes are always present
    pop = octagon_population(radius, rng, psi=psi, a=a)
    side = scale * max(4.0 * ratio, 3.0 * np.sqrt(np.sum(radius**2 / scale**2)))
    side = max(side, 2.6 * float(pop.circumradius.max()))  # needles (a = 1) must fit
    domain = Rectangle.centred(side, 0.8 * side, (3.0 * scale, -2.0 * scale))
    res = _pack(pop, domain, rng, eta=eta, interference=interference)
    assert res.placed.sum() >= 1
    if interference == "exact":
        _check(pop, res, domain)
    else:  # the tau rule may miss interferers: only the walls are guaranteed
        report = verify(_packing(pop, res, domain))
        assert report.n_outside == 0


def test_edge_angle_just_below_pi_keeps_the_envelope_order() -> None:
    """An edge at angle nextafter(pi, 0) reflects to just below 2 pi, not to 0."""
    import math

    from regopack.geometry.population import ShapeBatch

    dy = 4e-16  # atan2(dy, -1) == nextafter(pi, 0)
    q = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1 + 2 * dy]], dtype=float)
    th = -0.3
    rot = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    p = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float) @ rot.T
    shapes = ShapeBatch(np.concatenate([p, q]), np.array([0, 4, 8]), np.zeros(2))
    radius = np.sqrt(np.array([4.0, 4.0 + 2 * dy]) / np.pi)
    pop = Population(radius, np.zeros(2, dtype=np.int64), ("m",), shapes)
    domain = Rectangle.centred(20.0, 20.0)
    for seed in range(20):
        res = _pack(pop, domain, np.random.default_rng(seed))
        _check(pop, res, domain)


def test_polygons_with_collinear_vertices_do_not_overlap() -> None:
    from regopack.geometry.population import ShapeBatch

    p_out = np.array([[0.3, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]], dtype=float)
    th = 0.4
    rot = np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    q_out = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float) @ rot.T
    outlines = [q_out, p_out] * 60
    offsets = np.concatenate([[0], np.cumsum([len(o) for o in outlines])])
    shapes = ShapeBatch(np.concatenate(outlines), offsets, np.zeros(len(outlines)))
    radius = np.full(len(outlines), np.sqrt(4.0 / np.pi))
    pop = Population(radius, np.zeros(len(outlines), dtype=np.int64), ("m",), shapes)
    domain = Rectangle.centred(20.0, 20.0)
    for seed in range(3):
        res = _pack(pop, domain, np.random.default_rng(seed))
        _check(pop, res, domain)


def test_particle_that_fits_nowhere_still_updates_screening() -> None:
    """SPEC 4.7: the candidates are analysed (no arc) and record rmin = r_i."""
    from regopack.plugins.inserters.available_arc.candidates import first_candidate
    from regopack.plugins.inserters.available_arc.kernel import I_LEAVES
    from regopack.plugins.inserters.available_arc.state import ArcState

    rng = np.random.default_rng(0)
    pop = octagon_population(np.array([1.0, 1.0, 30.0]), rng)
    domain = Rectangle.centred(20.0, 20.0)
    st_ = ArcState(pop, domain, t=1.0, tau=None, linear=False)
    st_.insert(0, 0.0, 0.0)
    st_.insert(1, 5.0, 0.0)
    mq = st_.begin_particle(2)
    k, arcs = st_.find_site(2, 0, mq)
    assert k == -1 and arcs.shape == (0, 2)
    leaves = int(st_.packed.ipar[I_LEAVES])
    assert np.all(st_.packed.tree[leaves : leaves + 2] == 30.0)
    assert first_candidate(st_.packed.tree, leaves, 0, 2, 30.0, 1.0, False) == -1

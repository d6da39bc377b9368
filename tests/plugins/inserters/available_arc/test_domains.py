"""The available-arc and rsa inserters in every domain kind, checked by shapely oracles."""

from __future__ import annotations

import numpy as np
import pytest
import shapely
from arc_helpers import as_packing, change5_population, octagon_population, pack
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from regopack.base.errors import GeometryError
from regopack.geometry.domain import Circle, ConvexPolygon, Domain, PeriodicRectangle, Rectangle
from regopack.packing.core import Packing
from regopack.plugins.density.eta import EtaConfig, EtaController
from regopack.plugins.inserters.rsa import RandomSequentialAddition, RsaConfig
from regopack.plugins.sizes.change5 import Change5, Change5Config
from regopack.testing import extreme_radii
from regopack.verification.polygons import verify

PENTAGON = ((-100.0, -80.0), (90.0, -100.0), (120.0, 60.0), (0.0, 110.0), (-110.0, 40.0))


_population = change5_population
_pack = pack
_packing = as_packing


def brute_force_periodic_overlap(packing: Packing) -> float:
    """Largest overlap over all pairs and all nine images, relative to the smaller area."""
    geoms = packing.to_shapely()
    lx, ly = packing.domain.width, packing.domain.height
    worst = 0.0
    tree = shapely.STRtree(geoms)
    for sx in (-lx, 0.0, lx):
        for sy in (-ly, 0.0, ly):
            moved = shapely.transform(geoms, lambda c, sx=sx, sy=sy: c + (sx, sy))
            a, b = tree.query(moved, predicate="intersects")
            keep = a != b
            a, b = a[keep], b[keep]
            if len(a):
                inter = shapely.area(shapely.intersection(moved[a], geoms[b]))
                small = np.minimum(shapely.area(moved[a]), shapely.area(geoms[b]))
                worst = max(worst, float((inter / small).max()))
    return worst


DOMAINS = {
    "polygon": ConvexPolygon(PENTAGON),
    "circle": Circle(5.0, -3.0, 110.0),
    "periodic": PeriodicRectangle.centred(200.0, 160.0, (4.0, -2.0)),
}


@pytest.mark.parametrize("kind", list(DOMAINS))
def test_available_arc_fills_every_domain_kind_without_overlap(kind: str) -> None:
    domain = DOMAINS[kind]
    n = round(domain.area / Change5(Change5Config()).mean_area)
    pop, rng = _population(n, 3)
    res = _pack(pop, domain, rng)
    packing = _packing(pop, res, domain)
    report = verify(packing)
    assert report.ok, str(report)
    phi = packing.area()[packing.placed].sum() / domain.area
    assert phi > 0.75
    if kind == "periodic":
        assert brute_force_periodic_overlap(packing) < 1e-9
        c = packing.centre[packing.placed]
        assert np.all((c[:, 0] >= domain.xmin) & (c[:, 0] < domain.xmax))  # type: ignore[attr-defined]
        assert np.all((c[:, 1] >= domain.ymin) & (c[:, 1] < domain.ymax))  # type: ignore[attr-defined]
        # particles do cross the sides
        b = shapely.bounds(packing.to_shapely())
        assert np.any(b[:, 0] < domain.xmin) and np.any(b[:, 2] > domain.xmax)  # type: ignore[attr-defined]
    else:
        window = shapely.Polygon(domain.outline()).buffer(1e-9 * domain.width)
        assert shapely.contains(window, packing.to_shapely()).all()


@pytest.mark.parametrize("kind", list(DOMAINS))
def test_rsa_fills_every_domain_kind_without_overlap(kind: str) -> None:
    domain = DOMAINS[kind]
    pop, rng = _population(300, 4)
    rsa = RandomSequentialAddition(RsaConfig(max_attempts=200))
    res = rsa.pack(pop, domain, EtaController(EtaConfig()), rng)
    packing = _packing(pop, res, domain)
    assert packing.n_placed > 150
    report = verify(packing)
    assert report.ok, str(report)
    if kind == "periodic":
        assert brute_force_periodic_overlap(packing) < 1e-9


@pytest.mark.parametrize("kind", list(DOMAINS))
def test_linear_and_indexed_search_agree_in_every_domain_kind(kind: str) -> None:
    domain = DOMAINS[kind]
    out = []
    for search in ("linear", "indexed"):
        pop, rng = _population(400, 5)
        res = _pack(pop, domain, rng, eta=10.0, search=search)
        out.append(res.centre)
    np.testing.assert_array_equal(out[0], out[1])


def test_random_first_particle_in_a_circle_fits() -> None:
    domain = Circle(0.0, 0.0, 50.0)
    pop, rng = _population(80, 6)
    res = _pack(pop, domain, rng, first="random")
    assert verify(_packing(pop, res, domain)).ok


def test_first_particle_too_big_for_the_circle_is_skipped() -> None:
    rng = np.random.default_rng(1)
    radius = np.array([40.0, 1.0, 1.0, 1.0])
    pop = octagon_population(radius, rng)
    domain = Circle(0.0, 0.0, 30.0)
    res = _pack(pop, domain, rng)
    assert not res.placed[0]
    assert res.placed[1:].all()
    assert verify(_packing(pop, res, domain)).ok


def test_a_periodic_domain_too_small_for_its_particles_is_refused() -> None:
    rng = np.random.default_rng(1)
    pop = octagon_population(np.array([10.0, 1.0]), rng)
    with pytest.raises(GeometryError, match=r"periodic domain must be wider .* 4 x"):
        _pack(pop, PeriodicRectangle.centred(30.0, 100.0), rng)


def test_the_walled_rectangle_is_unchanged_by_the_other_kinds() -> None:
    # same particles in a rectangle and in the same rectangle given as a polygon
    rect = Rectangle.centred(150.0, 120.0)
    poly = ConvexPolygon(tuple(map(tuple, rect.outline())))
    pop, rng = _population(600, 7)
    a = _pack(pop, rect, rng)
    pop, rng = _population(600, 7)
    b = _pack(pop, poly, rng)
    assert verify(_packing(pop, b, poly)).ok
    # the two wall tests differ in rounding only: most of the packing is the same
    same = np.all(a.centre == b.centre, axis=1) | (np.isnan(a.centre).all(axis=1))
    assert same[:100].all()


@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(2, 50),
    ratio=st.sampled_from([1.0, 10.0, 1e2, 1e4]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
    psi=st.sampled_from([0.01, 1.0, 1000.0]),
    a=st.sampled_from([0.05, 1 / 3, 1.0]),
    kind=st.sampled_from(["polygon", "circle", "periodic"]),
    eta=st.sampled_from([0.0, 30.0]),
)
@settings(max_examples=120, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_no_overlap_and_nothing_outside_in_random_domains(
    seed, n, ratio, scale, psi, a, kind, eta
) -> None:
    rng = np.random.default_rng(seed)
    radius = extreme_radii(n, ratio, scale, rng)
    pop = octagon_population(radius, rng, psi=psi, a=a)
    size = scale * max(4.0 * ratio, 3.0 * np.sqrt(np.sum(radius**2 / scale**2)))
    size = max(size, 4.4 * float(pop.circumradius.max()))
    centre = (3.0 * scale, -2.0 * scale)
    domain: Domain
    if kind == "polygon":
        k = int(rng.integers(3, 9))
        t = np.sort(rng.uniform(0, 2 * np.pi, k)) if k > 3 else np.array([0.3, 2.4, 4.2])
        t = np.unique(np.round(t, 3))
        if len(t) < 3:
            t = np.array([0.3, 2.4, 4.2])
        r = 1.5 * size
        domain = ConvexPolygon(
            tuple((centre[0] + r * np.cos(x), centre[1] + r * np.sin(x)) for x in t)
        )
    elif kind == "circle":
        domain = Circle(centre[0], centre[1], 0.8 * size)
    else:
        domain = PeriodicRectangle.centred(size, 1.1 * size, centre)
    res = _pack(pop, domain, rng, eta=eta)
    packing = _packing(pop, res, domain)
    report = verify(packing)
    assert report.ok, str(report)
    if kind == "periodic":
        assert brute_force_periodic_overlap(packing) < 1e-9


def test_first_particle_in_a_thin_triangle_moves_in_from_the_centroid() -> None:
    # the centroid lies 1 from the base: a particle of radius 1.4 does not fit there
    tri = ConvexPolygon(((-10.0, 0.0), (10.0, 0.0), (0.0, 3.0)))
    rng = np.random.default_rng(2)
    pop = octagon_population(np.array([1.2, 0.3, 0.3]), rng)
    res = _pack(pop, tri, rng)
    assert res.placed[0]
    assert verify(_packing(pop, res, tri)).ok

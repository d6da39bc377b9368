"""Exact disks: the shape, insertion beside polygons, verification, files and contacts."""

from __future__ import annotations

import math

import numpy as np
import pytest
import shapely
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from regopack.geometry.domain import Circle, ConvexPolygon, Domain, PeriodicRectangle, Rectangle
from regopack.geometry.population import Population, concat_shapes
from regopack.packing.core import FORMAT_VERSION, Packing, load, save
from regopack.plugins.analyzers import Contacts, ContactsConfig
from regopack.plugins.density.eta import EtaConfig, EtaController
from regopack.plugins.inserters.available_arc import AvailableArc, AvailableArcConfig
from regopack.plugins.inserters.rsa import RandomSequentialAddition, RsaConfig
from regopack.plugins.shapes.disk import Disk
from regopack.plugins.shapes.octagon import OctagonConfig, RandomPolygon
from regopack.plugins.sizes.change5 import Change5, Change5Config
from regopack.testing import check_shape_generator, extreme_radii
from regopack.verification.polygons import verify

DOMAINS: dict[str, Domain] = {
    "rectangle": Rectangle.centred(120.0, 100.0, (3.0, -2.0)),
    "circle": Circle(1.0, 2.0, 62.0),
    "periodic": PeriodicRectangle.centred(120.0, 100.0),
    "polygon": ConvexPolygon(((-70.0, -55.0), (65.0, -60.0), (50.0, 60.0), (-60.0, 45.0))),
}


def _population(radius: np.ndarray, rng: np.random.Generator, share: float) -> Population:
    """Disks with probability ``share``, random octagons otherwise."""
    n = len(radius)
    disk = rng.random(n) < share
    a, b = np.flatnonzero(disk), np.flatnonzero(~disk)
    parts = [(a, Disk().generate(radius[a], rng))]
    parts.append((b, RandomPolygon(OctagonConfig(psi=1.0)).generate(radius[b], rng)))
    return Population(radius, disk.astype(np.int64), ("octagon", "disk"), concat_shapes(parts, n))


def _pack(pop: Population, domain: Domain, rng: np.random.Generator, eta: float = 0.0) -> Packing:
    res = AvailableArc(AvailableArcConfig()).pack(
        pop, domain, EtaController(EtaConfig(eta=eta)), rng
    )
    return Packing.from_parts(pop, res, domain, {}, 0)


def disk_gaps(packing: Packing) -> tuple[np.ndarray, np.ndarray]:
    """Brute force for a packing of disks: pair gaps over radius sums, and wall gaps."""
    idx = np.flatnonzero(packing.placed)
    c = packing.centre[idx]
    r = packing.rounding_radius[idx]
    d = c[:, None, :] - c[None, :, :]
    dom = packing.domain
    if isinstance(dom, PeriodicRectangle):
        period = np.array(dom.period)
        d = d - period * np.round(d / period)
    ratio = np.hypot(d[..., 0], d[..., 1]) / (r[:, None] + r[None, :])
    np.fill_diagonal(ratio, np.inf)
    if isinstance(dom, Circle):
        wall = dom.radius - np.hypot(c[:, 0] - dom.cx, c[:, 1] - dom.cy) - r
    elif isinstance(dom, ConvexPolygon):
        normal, offset = dom.halfplanes()
        wall = (offset[None, :] - c @ normal.T).min(axis=1) - r
    elif isinstance(dom, PeriodicRectangle):
        wall = np.full(len(idx), np.inf)
    else:
        assert isinstance(dom, Rectangle)
        wall = (
            np.minimum.reduce(
                [c[:, 0] - dom.xmin, dom.xmax - c[:, 0], c[:, 1] - dom.ymin, dom.ymax - c[:, 1]]
            )
            - r
        )
    return ratio, wall / r


def inscribed_overlap(packing: Packing) -> float:
    """Independent oracle for mixed packings: the largest overlap of inscribed polygons.

    Disks are drawn as inscribed 1024-gons, which lie inside the true disks:
    two of them overlap only where the true particles do.
    """
    idx = np.flatnonzero(packing.placed)
    geoms = []
    for j in idx:
        rho = packing.rounding_radius[j]
        if rho > 0:
            geoms.append(shapely.Point(packing.centre[j]).buffer(rho, quad_segs=256))
        else:
            geoms.append(shapely.Polygon(packing.polygon(j)))
    g = np.asarray(geoms, dtype=object)
    a, b = shapely.STRtree(g).query(g, predicate="intersects")
    keep = a < b
    a, b = a[keep], b[keep]
    if not len(a):
        return 0.0
    inter = shapely.area(shapely.intersection(g[a], g[b]))
    return float((inter / np.minimum(shapely.area(g[a]), shapely.area(g[b]))).max())


def test_disk_keeps_the_shape_contract() -> None:
    batch = check_shape_generator(Disk())
    assert batch.rounding is not None
    assert np.all(np.diff(batch.offsets) == 1)


@pytest.mark.parametrize("kind", list(DOMAINS))
def test_disks_pack_tangent_without_overlap_in_every_domain(kind: str) -> None:
    domain = DOMAINS[kind]
    rng = np.random.default_rng(4)
    n = round(domain.area / Change5(Change5Config()).mean_area)
    pop = _population(Change5(Change5Config()).sample(n, rng), rng, share=1.0)
    packing = _pack(pop, domain, rng)
    assert verify(packing).ok
    ratio, wall = disk_gaps(packing)
    assert ratio.min() > 1.0 - 1e-9
    assert wall.min() > -1e-9
    # every disk but the first touches another one (eta = 0: it sits on its candidate)
    touching = np.sum(np.abs(ratio - 1.0) < 1e-9, axis=1)
    assert np.count_nonzero(touching == 0) <= 1
    phi = packing.area()[packing.placed].sum() / domain.area
    assert phi > 0.75


@pytest.mark.parametrize("kind", list(DOMAINS))
def test_disks_beside_octagons(kind: str) -> None:
    domain = DOMAINS[kind]
    rng = np.random.default_rng(5)
    n = round(domain.area / Change5(Change5Config()).mean_area)
    pop = _population(Change5(Change5Config()).sample(n, rng), rng, share=0.5)
    packing = _pack(pop, domain, rng, eta=10.0)
    report = verify(packing)
    assert report.ok, str(report)
    if kind != "periodic":
        assert inscribed_overlap(packing) < 1e-9
    assert packing.n_placed > 0.9 * n


def test_rsa_places_disks_beside_octagons() -> None:
    rng = np.random.default_rng(6)
    pop = _population(rng.uniform(1.0, 4.0, 400), rng, share=0.5)
    for domain in DOMAINS.values():
        res = RandomSequentialAddition(RsaConfig(max_attempts=200)).pack(
            pop, domain, EtaController(EtaConfig()), rng
        )
        packing = Packing.from_parts(pop, res, domain, {}, 0)
        assert verify(packing).ok
        if not domain.periodic:
            assert inscribed_overlap(packing) < 1e-9


def _two(centres, radii, domain=None) -> Packing:
    n = len(radii)
    r = np.asarray(radii, dtype=float)
    pop = Population(r, np.zeros(n, dtype=np.int64), ("d",), Disk().generate(r, None))  # type: ignore[arg-type]
    from regopack.registry.interfaces import InsertionResult

    res = InsertionResult(np.asarray(centres, dtype=float), np.arange(n, dtype=np.int64))
    return Packing.from_parts(pop, res, domain or Rectangle(-10, 10, -10, 10), {}, 0)


@pytest.mark.parametrize(
    ("gap", "ok"),
    [(0.0, True), (1e-6, True), (-1e-7, True), (-1e-5, False), (-0.5, False)],
)
def test_verify_measures_disks_exactly(gap, ok) -> None:
    from regopack.verification.polygons import segment_fraction

    packing = _two([[0.0, 0.0], [3.0 + gap, 0.0]], [1.0, 2.0])
    report = verify(packing)
    assert report.ok is ok
    if not ok:  # the depth as the area of a segment of the smaller disk
        assert report.worst_overlap is not None
        expected = segment_fraction(np.array([-gap]), np.array([1.0]))[0]
        assert report.worst_overlap[2] == pytest.approx(expected, rel=1e-6)


def test_verify_finds_a_disk_overlapping_its_own_periodic_image() -> None:
    domain = PeriodicRectangle(0.0, 10.0, 0.0, 10.0)
    report = verify(_two([[5.0, 5.0]], [6.0], domain))
    assert not report.ok and report.worst_overlap is not None
    assert report.worst_overlap[:2] == (0, 0)
    assert verify(_two([[5.0, 5.0]], [4.9], domain)).ok


def test_verify_finds_a_bar_overlapping_its_own_periodic_image() -> None:
    from regopack.testing import packing_from_polygons

    domain = PeriodicRectangle(0.0, 10.0, 0.0, 10.0)
    bar = [(-0.5, 4.0), (11.5, 4.0), (11.5, 5.0), (-0.5, 5.0)]
    report = verify(packing_from_polygons([bar], domain=domain))
    assert not report.ok and report.worst_overlap is not None
    assert report.worst_overlap[0] == report.worst_overlap[1] == 0
    short = [(0.5, 4.0), (9.5, 4.0), (9.5, 5.0), (0.5, 5.0)]
    assert verify(packing_from_polygons([short], domain=domain)).ok


def test_verify_finds_a_disk_through_the_wall() -> None:
    packing = _two([[0.0, 0.0], [9.5, 0.0]], [1.0, 1.0])
    report = verify(packing)
    assert report.n_outside == 1
    r, d = 1.0, 0.5  # the disk pokes 0.5 through the wall: that segment of it is outside
    segment = r * r * math.acos((r - d) / r) - (r - d) * math.sqrt(2 * r * d - d * d)
    assert report.worst_outside == (1, pytest.approx(segment / (math.pi * r * r)))
    inside = _two([[0.0, 0.0], [5.0, 0.0]], [1.0, 1.0], Circle(0.0, 0.0, 6.0))
    assert verify(inside).ok
    across = _two([[0.0, 0.0], [5.5, 0.0]], [1.0, 1.0], Circle(0.0, 0.0, 6.0))
    assert verify(across).n_outside == 1


def test_packing_file_keeps_the_rounding(tmp_path) -> None:
    packing = _two([[0.0, 0.0], [3.0, 0.0]], [1.0, 2.0])
    np.testing.assert_allclose(packing.area(), [math.pi, 4.0 * math.pi], rtol=1e-15)
    save(packing, tmp_path / "p.npz")
    again = load(tmp_path / "p.npz")
    np.testing.assert_array_equal(again.rounding_radius, [1.0, 2.0])
    import json

    with np.load(tmp_path / "p.npz") as npz:
        assert json.loads(str(npz["meta"]))["format_version"] == FORMAT_VERSION == 2
    shapes = again.to_shapely()
    assert shapes[1].area == pytest.approx(4.0 * math.pi, rel=1e-3)


def test_contacts_of_tangent_disks_follow_the_lens() -> None:
    tol = 0.05
    packing = _two([[0.0, 0.0], [3.0, 0.0]], [1.0, 2.0])
    contacts = Contacts(ContactsConfig(tol=tol)).compute(packing, {})
    assert contacts.i.tolist() == [0] and contacts.j.tolist() == [1]
    # lens of two disks grown by tol/2 whose centres are 3 apart
    r1, r2, d = 1.0 + tol / 2, 2.0 + tol / 2, 3.0
    a1 = r1 * r1 * math.acos((d * d + r1 * r1 - r2 * r2) / (2 * d * r1))
    a2 = r2 * r2 * math.acos((d * d + r2 * r2 - r1 * r1) / (2 * d * r2))
    k = 0.5 * math.sqrt((-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2))
    assert contacts.area[0] == pytest.approx(a1 + a2 - k, rel=1e-12)  # two disks: exact
    assert contacts.width[0] == pytest.approx(k * 2 / d, rel=1e-12)  # the common chord
    np.testing.assert_allclose(contacts.normal[0], [1.0, 0.0], atol=1e-15)
    assert contacts.threshold.tolist() == [0.0]


def test_contacts_of_a_disk_on_an_octagon_are_within_the_polygon_margin() -> None:
    from regopack.testing import packing_from_polygons

    tol = 0.05
    sq = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
    base = packing_from_polygons([sq, [(x + 3.0, y) for x, y in sq]])
    # the second square replaced by a disk of radius 1 touching the first square's face
    packing = Packing(
        radius=np.array([2 / math.sqrt(math.pi), 1.0]),
        mineral=np.zeros(2, dtype=np.int64),
        mineral_names=("m",),
        vertices=np.concatenate([base.vertices[:4], [[0.0, 0.0]]]),
        offsets=np.array([0, 4, 5]),
        orientation=np.zeros(2),
        centre=np.array([[0.0, 0.0], [2.0, 0.0]]),
        insertion_index=np.array([0, 1]),
        domain=Rectangle(-5, 5, -5, 5),
        rounding=np.array([0.0, 1.0]),
    )
    contacts = Contacts(ContactsConfig(tol=tol)).compute(packing, {})
    assert contacts.i.tolist() == [0]
    assert abs(contacts.threshold[0]) <= 2 * 0.01 * tol  # tangent, to the polygon margin
    # the square's face grown by tol/2 cuts a segment of depth tol from the grown disk
    r, h = 1.0 + tol / 2, tol
    exact = r * r * math.acos((r - h) / r) - (r - h) * math.sqrt(2 * r * h - h * h)
    assert contacts.area[0] == pytest.approx(exact, rel=0.05)


@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(2, 40),
    ratio=st.sampled_from([1.0, 10.0, 1e2, 1e4]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
    kind=st.sampled_from(["rectangle", "circle", "periodic"]),
    eta=st.sampled_from([0.0, 30.0]),
)
@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
def test_random_disk_scenes_at_the_extremes(seed, n, ratio, scale, kind, eta) -> None:
    rng = np.random.default_rng(seed)
    radius = extreme_radii(n, ratio, scale, rng)
    pop = _population(radius, rng, share=1.0)
    size = scale * max(4.0 * ratio, 3.0 * np.sqrt(np.sum(radius**2 / scale**2)))
    size = max(size, 4.4 * float(radius.max()))
    domain: Domain
    if kind == "circle":
        domain = Circle(2.0 * scale, -scale, 0.8 * size)
    elif kind == "periodic":
        domain = PeriodicRectangle.centred(size, 1.1 * size, (scale, 0.0))
    else:
        domain = Rectangle.centred(size, 0.9 * size, (scale, 0.0))
    packing = _pack(pop, domain, rng, eta=eta)
    assert packing.n_placed >= 1
    ratio_, wall = disk_gaps(packing)
    assert ratio_.min() > 1.0 - 1e-9
    assert wall.min() > -1e-9
    assert verify(packing).ok


def _in_arcs(arcs: np.ndarray, phi: np.ndarray) -> np.ndarray:
    two_pi = 2 * np.pi
    out = np.zeros(phi.shape, dtype=bool)
    for a, b in arcs:
        out |= ((phi - a) % two_pi) < (b - a)
    return out


@settings(max_examples=150, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    nf=st.integers(0, 12),
    mode=st.sampled_from([0, 3]),
    scale=st.sampled_from([1e-6, 1.0, 1e6]),
)
def test_closed_form_disk_arcs_match_the_general_rounded_path(seed, nf, mode, scale) -> None:
    from regopack.plugins.inserters.available_arc.rounded import (
        RoundedInterferers,
        RoundedWalls,
        disk_arcs,
        rounded_arcs,
    )

    rng = np.random.default_rng(seed)
    rho = 2.0 * scale
    odx, ody = rng.uniform(-4, 4, (2, nf)) * scale
    orho = rng.uniform(0.3, 2.5, nf) * scale
    ox, oy = np.zeros((nf, 2)), np.zeros((nf, 2))
    oex, oey = np.tile([1.0, -1.0], (nf, 1)), np.zeros((nf, 2))
    on, slot = np.full(nf, 2), np.arange(nf)
    pc = rng.uniform(-1e3, 1e3, 2) * scale
    box = np.r_[pc[0] + rng.uniform(-3, 0.5) * scale, pc[0] + rng.uniform(-0.5, 3) * scale]
    box = np.r_[box, pc[1] + rng.uniform(-3, 0.5) * scale, pc[1] + rng.uniform(-0.5, 3) * scale]
    walls, woff, q = box.reshape(1, 4), np.zeros(1), np.zeros(1)
    # the general path sees cores of two vertices a hair apart (so that it does
    # not take its own shortcut to the closed form), which moves no arc end
    # by more than about 1e-10 radians
    hair = 1e-10 * scale
    ox[:, 1] = hair
    orad = np.full(nf, hair)
    w = (np.array([0.0, hair]), np.zeros(2), np.array([1.0, -1.0]), np.zeros(2))
    fast = disk_arcs(rho, pc[0], pc[1], nf, odx, ody, orho, mode, walls, box, woff, q, q, 0.0)
    # the envelope's vertex count is unsigned, as analyze_candidate passes it (an int64
    # here would compile a second specialization of the kernel for this test alone)
    others = RoundedInterferers(nf, slot, odx, ody, ox, oy, oex, oey, on, orad, orho)
    wl = RoundedWalls(mode, walls, box, woff, q, q, 1, 0.0)
    general = rounded_arcs(*w, np.uint64(2), rho, pc[0], pc[1], others, wl)
    phi = np.linspace(0, 2 * np.pi, 3001, endpoint=False)
    ends = np.concatenate([fast.ravel(), general.ravel()]) % (2 * np.pi)
    away = np.all(
        np.abs(((phi[:, None] - ends[None, :]) + np.pi) % (2 * np.pi) - np.pi) > 1e-6, axis=1
    )
    assert np.array_equal(_in_arcs(fast, phi)[away], _in_arcs(general, phi)[away])


@pytest.mark.parametrize("kind", ["periodic", "circle"])
def test_disk_scenes_are_reproducible_and_search_independent(kind: str) -> None:
    domain = DOMAINS[kind]
    out = []
    for search in ("linear", "indexed", "indexed"):
        rng = np.random.default_rng(8)
        pop = _population(Change5(Change5Config()).sample(250, rng), rng, share=0.5)
        res = AvailableArc(AvailableArcConfig(search=search)).pack(
            pop, domain, EtaController(EtaConfig(eta=5.0)), rng
        )
        out.append(res.centre)
    np.testing.assert_array_equal(out[0], out[1])
    np.testing.assert_array_equal(out[1], out[2])
